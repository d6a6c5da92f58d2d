#pragma once
// A load case: everything a run needs, read from a TOML file (SI units throughout).
// The section and key names are fixed by the project so that load cases stay portable.
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "indentsim/input/curve_csv.hpp"

namespace indentsim {

/// The scene: plane strain (a long cylinder or wedge on a block, per unit thickness) or
/// axisymmetry (a body of revolution on a cylindrical specimen).
enum class SceneKind { plane_strain, axisymmetric };
/// The kinematics of the specimen: small strain (the paper's), finite strain with contact on the
/// current configuration (docs/MODEL.md §12), or the one the scene needs (automatic: chosen with
/// the run's other "auto"s, choose_strain in run_configuration.hpp, §12.5).
enum class StrainChoice { small, finite, automatic };

struct GeometryInput {
  SceneKind kind = SceneKind::plane_strain;
  StrainChoice strain = StrainChoice::small;
  /// Not a key: why "auto" chose `strain`, when the choice was made before the run's own
  /// planning (pin_kinematics: a case planned for mesh.target_error, a fit's forward model).
  std::string strain_reason;
  double lx = 15e-3;  ///< block width of the half model, or the specimen's radius [m]
  double ly = 10e-3;  ///< block depth, or the specimen's height [m]
};

enum class PunchShapeKind { sphere, cone, flat, profile, area_function };

struct PunchInput {
  PunchShapeKind shape = PunchShapeKind::sphere;
  double radius = 2e-3;      ///< sphere (cylinder) radius, or the flat punch's radius R [m]
  double half_angle = 70.3;  ///< cone: angle between axis and face [degrees]
  double tip_radius = 0.0;   ///< cone: radius of the spherical cap blunting the tip (0: sharp) [m]
  std::string profile_file;  ///< profile: the CSV file it was read from, as given ("" when inline)
  std::vector<std::pair<double, double>> profile;  ///< profile: points (r, g(r)) [m]
  /// area_function: C0, C1, ... (up to C8) of Oliver and Pharr's A(h_c), SI (area_function_area).
  std::vector<double> area_coefficients;
};

/// The most coefficients Oliver and Pharr's area function takes (C0 ... C8).
inline constexpr std::size_t max_area_coefficients = 9;
/// The exponent of h_c that coefficient k multiplies: 2, 1, 1/2, 1/4, ..., 1/128.
double area_function_exponent(std::size_t k);
/// The projected contact area of a tip's area function at contact depth h >= 0 (Oliver and Pharr,
/// J. Mater. Res. 7, 1992, eq. 25): A(h) = C0 h^2 + C1 h + C2 h^(1/2) + ... + C8 h^(1/128), with
/// C_k in m^(2 - e_k) so that A is in m^2 for h in m; and its derivative dA/dh.
double area_function_area(const std::vector<double>& coefficients, double h);
double area_function_slope(const std::vector<double>& coefficients, double h);

enum class MaterialModel { elastic, ilyushin, j2 };
/// linear and power: Ilyushin's omega(e_u) (both models); power_law, ludwik, swift, voce and table:
/// the flow stress sigma_y(eps_p) of a tensile test (J2 only; docs/MODEL.md §12.1).
enum class HardeningLaw { linear, power, power_law, ludwik, swift, voce, table };
/// Beyond a hardening table's last point: flat (perfectly plastic) or along the last segment's slope.
enum class TableExtension { flat, last_slope };
/// The stress that the elastic law's D : e sets in finite strain (docs/MODEL.md §12.2): the
/// Cauchy stress (Abaqus's) or the Kirchhoff stress (Hencky's hyperelastic law).
enum class ElasticStressMeasure { cauchy, kirchhoff };
/// J2's flow rule (docs/MODEL.md §13.3): rate-independent (the plastic multiplier keeps the stress
/// on the yield surface), Perzyna's overstress eps_p' = rate0 <sigma_e / sigma_y(eps_p) - 1>^m, or
/// Norton's power-law creep eps_p' = A (sigma_e / sigma_ref)^m without a yield surface.
enum class RateLaw { none, perzyna, norton };

struct MaterialInput {
  MaterialModel model = MaterialModel::elastic;
  double E = 210e9;   ///< Young's modulus [Pa]
  double nu = 0.3;    ///< Poisson's ratio [-]
  double e0 = 0.027;  ///< elastic limit of the strain intensity [-]
  /// The uniaxial yield stress when the load case gave it instead of e0 [Pa] (e0 is then derived).
  std::optional<double> yield_stress;
  HardeningLaw hardening = HardeningLaw::linear;
  double kappa = 0.9;  ///< linear law: omega = kappa (1 - e0/e_u)
  double n = 0.3;      ///< power law: sigma_u ~ e_u^n; power_law, ludwik, swift: their exponent
  // The flow-stress laws' own parameters, given only with their law (which requires them).
  std::optional<double> K;          ///< ludwik, swift: strength coefficient [Pa]
  std::optional<double> prestrain;  ///< swift: eps_0, the plastic strain the curve starts from
  std::optional<double> Q;          ///< voce: saturation increase of the flow stress [Pa]
  std::optional<double> b;          ///< voce: saturation rate
  std::string hardening_table_file;  ///< table: the CSV file it was read from, as given ("" when inline)
  std::vector<std::pair<double, double>> hardening_points;  ///< table: points (eps_p, sigma [Pa])
  TableExtension table_extension = TableExtension::flat;
  ElasticStressMeasure elastic_stress = ElasticStressMeasure::cauchy;  ///< finite strain only
  RateLaw rate = RateLaw::none;  ///< j2 only
  // The flow rules' own parameters, given only with their rule (which requires them).
  std::optional<double> reference_strain_rate;  ///< perzyna: rate0 [1/s]
  std::optional<double> creep_coefficient;      ///< norton: A [1/s]
  std::optional<double> reference_stress;       ///< norton: sigma_ref [Pa]
  std::optional<double> rate_exponent;          ///< perzyna, norton: m >= 1

  /// The law is a flow-stress curve of J2 flow theory only (not an Ilyushin omega).
  bool flow_stress_law() const { return hardening != HardeningLaw::linear && hardening != HardeningLaw::power; }
};

/// The most [[layer]] tables a load case takes.
inline constexpr std::size_t max_layers = 100;

/// One layer of a coated specimen (docs/MODEL.md §14): a band of `thickness` below the layers
/// above it, of its own material, perfectly bonded to its neighbours.
struct LayerInput {
  double thickness = 0.0;  ///< [m]
  MaterialInput material;
};

/// What the load path steps (docs/MODEL.md §13.1): the punch's depth, the force P being the
/// result, or the force, the depth being one more unknown of each increment.
enum class LoadControlKind { depth, force };

struct LoadInput {
  LoadControlKind control = LoadControlKind::depth;
  /// The waypoints of the controlled quantity, from 0: depths alpha [m] under depth control,
  /// forces P [N; N/m in plane strain] under force control.
  std::vector<double> path{0.0, 5e-5};
  /// The time [s] at each waypoint of `path` (docs/MODEL.md §13.2), from 0 and increasing; empty
  /// when the path has no time.
  std::vector<double> times;
  int increments = 10;                  ///< total increments along the path
  /// Optional per-segment counts (`increments = [n1, n2, ...]`, one per segment of the path);
  /// empty when `increments` is a single total spread by segment length.
  std::vector<int> segment_increments;
  /// Force control: the depth the largest force reaches, as the depth pilot measured it
  /// (run_configuration.hpp); it sizes the mesh as the deepest waypoint does under depth control.
  /// case.toml records it, so that the case as run plans the same mesh without the pilot.
  std::optional<double> depth_estimate;

  /// The largest waypoint of the controlled quantity.
  double largest_target() const;
  /// The increments of the whole path.
  int total_increments() const;
  /// Every segment's increments (or the total) multiplied by `factor` >= 1: the same waypoints,
  /// each increment split into `factor`.
  void multiply_increments(int factor);
};

enum class ElementChoice { automatic, q1, bbar };

/// A tip whose contact has no length scale, or only one far below its contact (a rounding): a cone,
/// or a calibrated tip's area function (A ~ C0 h^2 beyond its rounding).  Its contact edge sweeps
/// the contact zone node by node, and under plastic flow the whole contact is near-incompressible.
inline bool sharp_tip(PunchShapeKind shape) {
  return shape == PunchShapeKind::cone || shape == PunchShapeKind::area_function;
}

/// The default mesh.contact_nodes under a sharp tip (load_case.cpp says why).
inline constexpr int cone_contact_nodes = 30;

/// How a run estimates its own discretization error (error_estimate.hpp): a companion run on a
/// mesh with half the contact nodes and the orders measured in the work-precision study
/// ("richardson"), a second companion at a quarter to observe the order ("observed"), or none.
enum class ErrorEstimateChoice { richardson, observed, off };

struct MeshInput {
  ElementChoice element = ElementChoice::automatic;  ///< "auto" | "q1" | "bbar"
  int contact_nodes = 20;  ///< fine-zone elements across the estimated final contact half-width
                           ///< (cone_contact_nodes when the key is absent and the punch is a cone)
  std::optional<double> contact_half_width;  ///< override of the estimate a* [m]
  std::optional<double> fine_width;          ///< override: width of the uniform zone [m]
  std::optional<double> fine_depth;          ///< override: depth of the uniform zone [m]
  std::optional<double> growth;              ///< override: geometric growth ratio of the far field
  ErrorEstimateChoice error_estimate = ErrorEstimateChoice::richardson;
  /// The relative error of the final P asked for: the run chooses contact_nodes (error_estimate.hpp).
  std::optional<double> target_error;
  /// The pilot run's plastic zone as it grew: [depth h, width, depth below the surface] [m] at the
  /// pilot's increments.  case.toml records it (with contact_half_width, the pilot's other
  /// measurement) so that the case as run plans the same condensed near field without a pilot.
  std::vector<std::array<double, 3>> plastic_zone;
  /// The largest mesh a case may plan, in unknowns: a slip (a cone of half-angle 1e-300, a depth
  /// in nm written as m) otherwise plans millions of them and runs for minutes before it fails.
  /// Raise it for a mesh that is meant to be so large.
  int max_unknowns = 2'000'000;
};

struct OutputInput {
  std::string dir = "out";  ///< output folder (relative to the working directory)
  int fields_every = 0;     ///< VTU every N increments (0: the final state only)
  std::vector<double> profile_depths;  ///< depths [m] of the stress profiles besides the surface
  int checkpoint_every = 10;  ///< checkpoint every N increments and at the end (0: only on SIGINT/SIGTERM)
  int keep_checkpoints = 2;   ///< newest checkpoints kept besides every reversal's (0 = "all")
};

enum class LinearSolverChoice { automatic, klu, cholmod };
/// Whether the linear-elastic far field is condensed out of the Newton systems (docs/DESIGN.md 7).
enum class FarFieldChoice { automatic, condense, full };
/// How a Newton iteration solves its linear system (docs/DESIGN.md §8): GMRES preconditioned by a
/// factorization kept across the iterations (krylov), a factorization per iteration that a
/// converging iteration may keep (reuse, a chord step), or a factorization every iteration
/// (fresh); automatic: krylov for an inelastic specimen, reuse for an elastic one.
enum class JacobianChoice { automatic, reuse, fresh, krylov };

struct SolverInput {
  LinearSolverChoice linear = LinearSolverChoice::klu;  ///< "klu" (default) | "cholmod" | "auto"
  FarFieldChoice far_field = FarFieldChoice::automatic;  ///< "auto" (default) | "condense" | "full"
  JacobianChoice jacobian = JacobianChoice::automatic;   ///< "auto" (default) | "krylov" | "reuse" | "fresh"
  double tolerance = 1e-11;  ///< residual max-norm relative to E* x max depth
  int max_newton = 50;       ///< Newton iterations per increment before a cutback
  int max_cutbacks = 10;     ///< halvings of one increment before the run stops
};

/// How load-unload curves are analysed (indentation_analysis.hpp): Oliver-Pharr's constants and
/// the indenter's elasticity.  They do not change the simulation.
struct AnalysisInput {
  std::vector<double> fit_range{0.2, 0.98};  ///< unloading fit over these fractions of P_max
  std::optional<double> epsilon;             ///< h_c = h_max - epsilon P_max / S (default by shape)
  double beta = 1.0;                         ///< E_r = sqrt(pi) / (2 beta) S / sqrt(A) (1.034: Berkovich)
  std::optional<double> indenter_E;          ///< [Pa]; none: a rigid indenter
  double indenter_nu = 0.07;                 ///< diamond
  /// A coated run's analysis warns where the substrate moves E_r or H by more than this fraction
  /// from the film's own (docs/MODEL.md §14.4).
  double substrate_tolerance = 0.02;
};

/// How the contact conditions become equations (docs/MODEL.md §3).
enum class ContactDiscretizationChoice {
  node_to_rigid,  ///< the seed paper's: a complementarity row per surface node
  integrated_gap  ///< the penetration integrated over the surface segments, a penalty pressure
};

struct ContactInput {
  ContactDiscretizationChoice discretization = ContactDiscretizationChoice::node_to_rigid;
  /// kappa of integrated_gap's penalty eps = kappa c / m (a node's stiffness over its surface):
  /// the penetration under a pressure p is about p h / (kappa E*).
  double penalty = 100.0;
  /// Coulomb's coefficient mu between specimen and punch (docs/MODEL.md §3.3): 0 frictionless,
  /// +infinity sticking.
  double friction = 0.0;
};

struct LoadCase {
  std::string source = "<defaults>";  ///< file it was read from, for messages
  GeometryInput geometry;
  PunchInput punch;
  MaterialInput material;  ///< the substrate's (the whole specimen's without layers)
  /// The layers on the substrate, from the surface down (docs/MODEL.md §14); empty for a
  /// homogeneous specimen.
  std::vector<LayerInput> layers;
  LoadInput load;
  MeshInput mesh;
  OutputInput output;
  SolverInput solver;
  ContactInput contact;
  AnalysisInput analysis;

  /// The deepest point of the path [m]: the deepest waypoint under depth control; under force
  /// control the depth estimate (0 before the pilot has measured it).
  double max_depth() const;

  /// The material regions of the specimen (docs/MODEL.md §14.1): region 0 the substrate, region k
  /// layer k from the surface (k = 1 ... layers.size()).
  std::size_t regions() const { return 1 + layers.size(); }
  const MaterialInput& region_material(std::size_t region) const {
    return region == 0 ? material : layers[region - 1].material;
  }
  /// The material at the surface, which the punch meets: the top layer's, or the substrate's.
  const MaterialInput& surface_material() const { return layers.empty() ? material : layers.front().material; }
  /// Some region is not linear elastic.
  bool any_inelastic() const;
  /// Some region flows by `rule`; any_rate_dependent: by a rule other than none.
  bool any_rate(RateLaw rule) const;
  bool any_rate_dependent() const;
  /// The depths [m] of the interfaces below the surface, increasing: the bottom of each layer.
  std::vector<double> interface_depths() const;
  /// The region of the material at depth d below the surface (an interface belongs to the region
  /// above it).
  std::size_t region_at_depth(double depth) const;
};

/// Reads and validates a load case.  `overrides` are "section.key=value" strings
/// (the CLI's --set) applied before validation; values are parsed as TOML values,
/// falling back to a plain string.  Throws InputError naming file, key and problem.
LoadCase read_load_case(const std::filesystem::path& file,
                        const std::vector<std::string>& overrides = {});

/// A double as TOML text: the shortest form that reads back to the same double, always a float.
std::string toml_number(double value);
/// A TOML basic string holding `s`: how a path or a word is passed through a "key=value" override.
std::string toml_string(const std::string& s);

/// Parses a load case from TOML text (tests, fuzzing); `source` names it in messages.
LoadCase parse_load_case(const std::string& toml_text, const std::string& source,
                         const std::vector<std::string>& overrides = {});

/// What `indentsim analyze` reads besides a measured curve: the indenter (every punch.* key;
/// punch.shape required), the scene (geometry.kind, axisymmetric unless given), the analysis.*
/// keys, the specimen's material.nu (optional: for the specimen modulus) and the [curve] keys
/// (depth_column, force_column, depth_unit, force_unit; see curve_csv.hpp).  No other key.
struct AnalysisSetup {
  std::string source;  ///< the TOML file, or "--set"
  SceneKind scene = SceneKind::axisymmetric;
  PunchInput punch;
  AnalysisInput analysis;
  std::optional<double> specimen_nu;
  CurveColumns columns;
};

/// Reads an analysis setup from a small TOML file (or none: only `overrides`); throws InputError.
AnalysisSetup read_analysis_setup(const std::optional<std::filesystem::path>& file,
                                  const std::vector<std::string>& overrides);

/// Checks every physical constraint (E > 0, -1 < nu < 0.5, ...); throws InputError.
void validate(const LoadCase& load_case);

/// The load case as TOML (every key, defaults filled in): what a run actually used.
std::string to_toml(const LoadCase& load_case);

/// The smallest elastic-limit strain e0 a case may give (directly or as sigma_y / (3 mu)): solids
/// yield at 1e-5 to 1e-1; below 1e-9 the laws' ratios e_u / e0 leave double precision.
inline constexpr double min_elastic_limit_strain = 1e-9;
/// The uniaxial yield stress of Ilyushin's law: sigma_y = sigma_u(e0) = 3 mu e0, mu = E / (2 (1 + nu)).
double yield_stress_of_e0(double e0, double E, double nu);
/// Its inverse, e0 = sigma_y / (3 mu): how material.yield_stress becomes e0.
double e0_of_yield_stress(double yield_stress, double E, double nu);

/// One load-case key as `indentsim keys` and the README describe it.
struct KeyDescription {
  std::string key;            ///< section.name
  std::string type, default_value, range, unit, help;
  bool required = false;
  /// default_value is a value of the key (TOML text), not words about it ("from e0").
  bool default_is_value = true;
};
/// Every key a load case accepts, in case.toml's order, from the same declarations the reader uses.
std::vector<KeyDescription> describe_keys();
/// The keys as a Markdown table (the README's).
std::string keys_markdown();
/// What is wrong with `value` for the number key `key` ("material.E") against the interval its
/// declared range words state ("must lie in [1e-100, 1e100] (got 1e+300)"), or nullopt when it
/// lies inside, or the key declares no interval.  The fit holds its bounds to it.
std::optional<std::string> declared_interval_problem(const std::string& key, double value);
/// The magnitudes a key's values plausibly have, as its declaration states them (implausible_values
/// warns outside them), or nullopt when it states none.
struct PlausibleMagnitudes {
  double low = 0.0, high = 0.0;
  std::string of_what;  ///< "the moduli of solids (soft gels to diamond)"
};
std::optional<PlausibleMagnitudes> plausible_magnitudes(const std::string& key);

/// Warnings for values given outside the magnitudes of their kind (a modulus of 70 Pa, a yield
/// stress of 300 Pa, a depth of 50 m), each naming the key as the case gave it: most are unit
/// slips, which run and give results off by 1e3 to 1e9.
std::vector<std::string> implausible_values(const LoadCase& lc);

/// The first key among the physics and mesh keys (geometry, punch, material, mesh) where two
/// load cases differ, or "" if they agree: what a resumed run may not change.
std::string first_physics_difference(const LoadCase& a, const LoadCase& b);

std::string to_string(MaterialModel model);
std::string to_string(SceneKind kind);
std::string to_string(StrainChoice strain);
std::string to_string(LoadControlKind control);
std::string to_string(PunchShapeKind shape);
std::string to_string(HardeningLaw law);
std::string to_string(TableExtension extension);
std::string to_string(ElasticStressMeasure measure);
std::string to_string(RateLaw law);

}  // namespace indentsim
