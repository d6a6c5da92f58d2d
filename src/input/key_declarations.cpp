#include "key_declarations.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

#include "indentsim/base/version.hpp"

namespace indentsim {

namespace input_detail {

std::optional<Bounds> bounds_of(const std::string& range) {
  const auto number = [](const std::string& text) -> std::optional<double> {
    std::size_t used = 0;
    try {
      const double x = std::stod(text, &used);
      if (text.find_first_not_of(' ', used) == std::string::npos) return x;
    } catch (const std::exception&) {
    }
    return std::nullopt;
  };
  const std::string head = range.substr(0, range.find(range.front() == '(' || range.front() == '[' ? ')' : ','));
  Bounds b;
  if (range.rfind(">=", 0) == 0 || range.rfind("> ", 0) == 0) {
    const bool closed = range[1] == '=';
    const auto lower = number(head.substr(closed ? 2 : 1));
    if (!lower) return std::nullopt;
    b.lower = *lower;
    b.lower_closed = closed;
    b.words = head;
    return b;
  }
  if (range.front() != '(' && range.front() != '[') return std::nullopt;
  const std::size_t close = range.find_first_of(")]");
  const std::size_t comma = range.find(',');
  if (close == std::string::npos || comma == std::string::npos || comma > close) return std::nullopt;
  const auto lower = number(range.substr(1, comma - 1)), upper = number(range.substr(comma + 1, close - comma - 1));
  if (!lower || !upper) return std::nullopt;
  b.lower = *lower;
  b.upper = *upper;
  b.lower_closed = range.front() == '[';
  b.upper_closed = range[close] == ']';
  b.two_sided = true;
  b.words = range.substr(0, close + 1);
  return b;
}

std::optional<std::string> Bounds::problem(double value) const {
  const bool above = lower_closed ? value >= lower : value > lower;
  const bool below = upper_closed ? value <= upper : value < upper;
  if (above && below) return std::nullopt;  // NaN is neither
  return two_sided ? fmt::format("must lie in {} (got {})", words, value) : fmt::format("must be {} (got {})", words, value);
}

void check_declared_ranges(const LoadCase& lc, const std::string& section) {
  for (const KeyDeclaration& k : key_declarations())
    if (k.check && section == k.section) k.check(lc);
}

namespace {

/// The check of a number key's declared interval, with `why` after the message (a reason the
/// bound is where it is); for an optional key only when it is given.
template <class Access>
void attach_bounds(KeyDeclaration& k, Access access, const char* why = "") {
  const auto bounds = bounds_of(k.range);
  if (!bounds) return;
  const std::string key = std::string(k.section) + "." + k.name;
  k.check = [=, b = *bounds](const LoadCase& lc) {
    const auto& value = access(lc);
    if constexpr (std::is_same_v<std::decay_t<decltype(value)>, std::optional<double>>) {
      if (!value) return;
      if (auto problem = b.problem(*value)) throw InputError(lc.source, key, *problem + why);
    } else {
      if (auto problem = b.problem(static_cast<double>(value))) throw InputError(lc.source, key, *problem + why);
    }
  };
}

}  // namespace

// The declarations, section by section in the order case.toml shows them.
template <class Access>
KeyDeclaration number_key(KeyDeclaration k, Access access, const char* why = "") {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_number(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> { return toml_number(access(lc)); };
  attach_bounds(k, access, why);
  return k;
}
template <class Access>
KeyDeclaration optional_number_key(KeyDeclaration k, Access access) {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_optional_number(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> {
    const auto& value = access(lc);
    if (!value) return std::nullopt;
    return toml_number(*value);
  };
  attach_bounds(k, access);
  return k;
}
template <class Access>
KeyDeclaration integer_key(KeyDeclaration k, Access access) {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_integer(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> { return std::to_string(access(lc)); };
  attach_bounds(k, access);
  return k;
}
template <class Access>
KeyDeclaration numbers_key(KeyDeclaration k, Access access) {
  const std::string section = k.section, name = k.name;
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_number_array(section, name, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> { return toml_numbers(access(lc)); };
  return k;
}
template <class E, std::size_t N, class Access>
KeyDeclaration choice_key(KeyDeclaration k, const Choice<E> (&names)[N], Access access) {
  const std::string section = k.section, name = k.name;
  const Choice<E>* words = names;
  std::vector<std::string> accepted;
  for (std::size_t i = 0; i < N; ++i) accepted.emplace_back(fmt::format("\"{}\"", names[i].name));
  k.range = "one of " + join(accepted);
  k.read = [=](const Reader& r, LoadCase& lc) { r.read_choice(section, name, words, N, access(lc)); };
  k.write = [=](const LoadCase& lc) -> std::optional<std::string> {
    for (std::size_t i = 0; i < N; ++i)
      if (words[i].value == access(lc)) return fmt::format("\"{}\"", words[i].name);
    return std::nullopt;
  };
  return k;
}

/// Declares the magnitudes plausible for a key whose values `access` gives (a number, an
/// optional one or an array: only what the case gives is judged).
template <class Access>
KeyDeclaration plausible(KeyDeclaration k, double low, double high, const char* of_what, Access access) {
  k.plausible = KeyDeclaration::Plausible{low, high, of_what};
  k.magnitudes = [=](const LoadCase& lc) -> std::vector<double> {
    const auto& value = access(lc);
    using V = std::decay_t<decltype(value)>;
    if constexpr (std::is_same_v<V, std::optional<double>>) {
      if (!value) return {};
      return {*value};
    } else if constexpr (std::is_same_v<V, std::vector<double>>) {
      return value;
    } else {
      return {static_cast<double>(value)};
    }
  };
  return k;
}

/// A hardening curve's key, which Norton's creep has no use for (and refuses): not written under it.
KeyDeclaration hardening_curve_key(KeyDeclaration k) {
  const auto write = k.write;
  k.write = [write](const LoadCase& lc) -> std::optional<std::string> {
    if (lc.material.rate == RateLaw::norton) return std::nullopt;
    return write(lc);
  };
  return k;
}

const std::vector<KeyDeclaration>& key_declarations() {
  static const std::vector<KeyDeclaration> keys = [] {
    std::vector<KeyDeclaration> k;
    k.push_back(choice_key({"geometry", "kind", "choice", "", "",
                            "plane_strain (a long punch on a block, P per unit thickness in N/m), axisymmetric (a "
                            "punch of revolution on a cylindrical specimen, P in N)"},
                           scene_names, [](auto& c) -> auto& { return c.geometry.kind; }));
    k.push_back(choice_key({"geometry", "strain", "choice", "", "",
                            "small (the paper's: linearized strain, the gap at the undeformed surface); finite "
                            "(total Lagrangian, Hencky strain, J2 in the multiplicative split, F-bar for bbar, the gap "
                            "at the surface's current position, with or without friction; KLU; node_to_rigid "
                            "contact); auto (finite where its geometric share of P, about 0.25 alpha / a elastic and "
                            "0.06 alpha / a plastic with a the punch's own (Sneddon) contact estimate at the deepest "
                            "point, exceeds mesh.target_error or 2e-3; small where finite strain is not built: the "
                            "integrated gap, cholmod)"},
                           strain_names, [](auto& c) -> auto& { return c.geometry.strain; }));
    {
      const auto lx = [](auto& c) -> auto& { return c.geometry.lx; };
      const auto ly = [](auto& c) -> auto& { return c.geometry.ly; };
      k.push_back(plausible(number_key({"geometry", "lx", "number", "> 0", "m",
                                        "half width of the block (plane strain: the model is the half x >= 0 of a "
                                        "symmetric block); the specimen's radius in axisymmetry (its outer side free)",
                                        true},
                                       lx),
                            1e-8, 10.0, "the sizes of specimens", lx));
      k.push_back(plausible(number_key({"geometry", "ly", "number", "> 0, > the deepest depth", "m",
                                        "depth of the block, height of the specimen (its base is clamped)", true},
                                       ly),
                            1e-8, 10.0, "the sizes of specimens", ly));
    }
    k.push_back(choice_key({"punch", "shape", "choice", "", "",
                            "sphere (circular profile of radius R: a sphere in axisymmetry, a cylinder in plane "
                            "strain; \"cylinder\" is a synonym), cone (a wedge in plane strain), flat (flat-ended), "
                            "profile (a measured tip), area_function (a calibrated tip's A(h_c), as the axisymmetric profile of "
                            "equal area)"},
                           shape_names, [](auto& c) -> auto& { return c.punch.shape; }));
    {
      KeyDeclaration radius{"punch", "radius", "number", "> 0, > the deepest depth (sphere)", "m",
                            "sphere and flat: the punch radius R (required for them, refused for other shapes)"};
      radius.default_words = "none: required for sphere and flat";
      radius.plausible = KeyDeclaration::Plausible{1e-9, 1.0, "the radii of indenters"};
      radius.magnitudes = [](const LoadCase& lc) -> std::vector<double> {
        if (lc.punch.shape != PunchShapeKind::sphere && lc.punch.shape != PunchShapeKind::flat) return {};
        return {lc.punch.radius};
      };
      radius.read = [](const Reader& r, LoadCase& lc) { r.read_number("punch", "radius", lc.punch.radius); };
      radius.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::sphere && lc.punch.shape != PunchShapeKind::flat) return std::nullopt;
        return toml_number(lc.punch.radius);
      };
      k.push_back(radius);
    }
    {
      KeyDeclaration angle{"punch", "half_angle", "number", "(0, 90)", "degrees",
                           "cone: angle between axis and face (70.3: Berkovich- and Vickers-equivalent; required for "
                           "the cone)"};
      angle.default_words = "none: required for the cone";
      // Cube-corner-equivalent 42.3, Berkovich- and Vickers-equivalent 70.3; conical tips 30 to 75.
      angle.plausible = KeyDeclaration::Plausible{15.0, 85.0, "the half-angles of indenters"};
      angle.magnitudes = [](const LoadCase& lc) -> std::vector<double> {
        if (lc.punch.shape != PunchShapeKind::cone) return {};
        return {lc.punch.half_angle};
      };
      angle.read = [](const Reader& r, LoadCase& lc) { r.read_number("punch", "half_angle", lc.punch.half_angle); };
      angle.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::cone) return std::nullopt;
        return toml_number(lc.punch.half_angle);
      };
      k.push_back(angle);
    }
    {
      KeyDeclaration tip{"punch", "tip_radius", "number", ">= 0, cap within the specimen", "m",
                         "cone: radius of the spherical cap tangent to the face (a blunt tip; 0 = sharp)"};
      tip.plausible = KeyDeclaration::Plausible{1e-9, 1e-2, "the tip radii of indenters"};
      tip.magnitudes = [](const LoadCase& lc) -> std::vector<double> {
        if (lc.punch.shape != PunchShapeKind::cone || lc.punch.tip_radius == 0.0) return {};
        return {lc.punch.tip_radius};
      };
      tip.read = [](const Reader& r, LoadCase& lc) { r.read_number("punch", "tip_radius", lc.punch.tip_radius); };
      tip.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::cone) return std::nullopt;
        return toml_number(lc.punch.tip_radius);
      };
      k.push_back(tip);
    }
    {
      KeyDeclaration file{"punch", "profile", "string", "a CSV file of r, g(r)", "m",
                          "profile: a measured tip, rows r, g(r) from r = 0, g(0) = 0, r increasing, g not "
                          "decreasing (a header row is allowed); relative to the load case's folder"};
      file.read = [](const Reader& r, LoadCase& lc) { r.read_string("punch", "profile", lc.punch.profile_file); };
      file.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::profile || lc.punch.profile_file.empty()) return std::nullopt;
        std::ostringstream text;
        text << toml::value<std::string>(lc.punch.profile_file);
        return text.str() + " read into profile_points";
      };
      file.derived = true;  // case.toml holds the points themselves: a resumed run needs no file
      file.default_words = "none: profile needs it or profile_points";
      k.push_back(file);
    }
    {
      KeyDeclaration points{"punch", "profile_points", "array of [r, g] pairs", "as punch.profile", "m",
                            "profile: the tip's points inline, instead of punch.profile (case.toml writes them so)"};
      points.default_words = "none";
      points.plausible = KeyDeclaration::Plausible{1e-9, 1.0, "the sizes of indenter tips (the last point's r)"};
      points.magnitudes = [](const LoadCase& lc) -> std::vector<double> {
        if (lc.punch.shape != PunchShapeKind::profile || lc.punch.profile.empty()) return {};
        return {lc.punch.profile.back().first};
      };
      points.read = [](const Reader& r, LoadCase& lc) { r.read_points("punch", "profile_points", lc.punch.profile); };
      points.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::profile) return std::nullopt;
        std::string text = "[";
        for (std::size_t i = 0; i < lc.punch.profile.size(); ++i)
          text += fmt::format("{}[{}, {}]", i ? ", " : "", toml_number(lc.punch.profile[i].first),
                              toml_number(lc.punch.profile[i].second));
        return text + "]";
      };
      k.push_back(points);
    }
    {
      KeyDeclaration area{"punch", "area_coefficients", "array of numbers", "1 to 9; A(h_c) increasing", "SI",
                          "area_function: C0, C1, ..., C8 of A(h_c) = C0 h_c^2 + C1 h_c + C2 h_c^(1/2) + ... + "
                          "C8 h_c^(1/128), C_k in m^(2 - e_k) for h_c in m (C0 = 24.5 for the ideal Berkovich)"};
      area.default_words = "none: area_function needs it";
      area.read = [](const Reader& r, LoadCase& lc) {
        r.read_number_array("punch", "area_coefficients", lc.punch.area_coefficients);
      };
      area.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.punch.shape != PunchShapeKind::area_function) return std::nullopt;
        return toml_numbers(lc.punch.area_coefficients);
      };
      k.push_back(area);
    }
    k.push_back(choice_key({"material", "model", "choice", "", "",
                            "elastic; ilyushin (deformation theory, the paper's); j2 (flow theory)", true},
                           model_names, [](auto& c) -> auto& { return c.material.model; }));
    {
      const auto E = [](auto& c) -> auto& { return c.material.E; };
      k.push_back(plausible(number_key({"material", "E", "number", "[1e-100, 1e100]", "Pa", "Young's modulus", true}, E,
                                       // Stresses and forces are E times O(1) numbers and their squares are
                                       // formed (norms, J2): beyond these bounds double precision cannot hold them.
                                       ": beyond what double precision can solve (the results scale with E: use SI "
                                       "units, pascals)"),
                            1e3, 2e12, "the moduli of solids (soft gels to diamond)", E));
    }
    k.push_back(number_key({"material", "nu", "number", "(-1, 0.5)", "", "Poisson's ratio", true},
                           [](auto& c) -> auto& { return c.material.nu; }));
    {
      KeyDeclaration e0 = number_key({"material", "e0", "number", "[1e-9, 1)", "",
                                      "elastic limit of the strain intensity e_u; the uniaxial yield stress is sigma_y = "
                                      "3 mu e0 = E e0 3 / (2 (1 + nu)) (give e0 or yield_stress, not both; not for "
                                      "swift and table, whose curve starts at its own yield stress)"},
                                     [](auto& c) -> auto& { return c.material.e0; },
                                     ": a strain (solids yield at 1e-5 to 1e-1; below 1e-9 the law's ratio e_u / e0 "
                                     "leaves double precision)");
      const auto write = e0.write;
      e0.write = [write](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.material.hardening == HardeningLaw::swift || lc.material.hardening == HardeningLaw::table)
          return std::nullopt;
        return write(lc);
      };
      k.push_back(hardening_curve_key(e0));
    }
    {
      KeyDeclaration ys{"material", "yield_stress", "number", "> 0", "Pa",
                        "uniaxial yield stress sigma_y, instead of e0 (e0 = sigma_y / (3 mu))"};
      ys.read = [](const Reader& r, LoadCase& lc) { r.read_optional_number("material", "yield_stress", lc.material.yield_stress); };
      ys.write = [](const LoadCase& lc) -> std::optional<std::string> {
        const auto& m = lc.material;
        // swift and table start at their own curve's yield stress (shown, as derived).
        if (m.hardening == HardeningLaw::swift && m.K && m.prestrain)
          return toml_number(*m.K * std::pow(*m.prestrain, m.n));
        if (m.hardening == HardeningLaw::table && !m.hardening_points.empty())
          return toml_number(m.hardening_points.front().second);
        return toml_number(m.yield_stress.value_or(yield_stress_of_e0(m.e0, m.E, m.nu)));
      };
      ys.derived = true;
      ys.default_words = "from e0";
      ys.plausible = KeyDeclaration::Plausible{1e5, 3e10, "the yield stresses of solids"};
      ys.magnitudes = [](const LoadCase& lc) -> std::vector<double> {
        if (!lc.material.yield_stress) return {};
        return {*lc.material.yield_stress};
      };
      k.push_back(hardening_curve_key(ys));
    }
    k.push_back(hardening_curve_key(choice_key({"material", "hardening", "choice", "", "",
                            "Ilyushin's omega(e_u), both models -- linear: omega = kappa (1 - e0/e_u); power: omega = "
                            "1 - (e0/e_u)^(1-n).  A tensile test's flow stress sigma(eps_p), j2 only -- power_law: "
                            "sigma_y (1 + E eps_p / sigma_y)^n; ludwik: sigma_y + K eps_p^n; swift: K (prestrain + "
                            "eps_p)^n; voce: sigma_y + Q (1 - exp(-b eps_p)); table: hardening_table's points"},
                           hardening_names, [](auto& c) -> auto& { return c.material.hardening; })));
    k.push_back(hardening_curve_key(number_key({"material", "kappa", "number", "[0, 1)", "",
                            "linear law: post-yield slope of sigma_u(e_u) is (1 - kappa) 3 mu"},
                           [](auto& c) -> auto& { return c.material.kappa; })));
    k.push_back(hardening_curve_key(number_key({"material", "n", "number", "[0, 1)", "",
                            "hardening exponent -- power: sigma_u grows as e_u^n beyond e0 (n > 0); power_law, swift "
                            "(n = 0: perfectly plastic), ludwik (n > 0)"},
                           [](auto& c) -> auto& { return c.material.n; })));
    // The flow-stress laws' own parameters: written to case.toml only under their law, required
    // there (check_hardening_keys), refused under another.
    // A number written to case.toml only when the case's `choice` (its hardening law, its flow rule)
    // is one of `users`: another law's parameter is not part of the case.
    const auto number_used_by = [&](KeyDeclaration d, auto access, auto users, auto choice, const char* needed_by) {
      KeyDeclaration key = optional_number_key(std::move(d), access);
      key.write = [=](const LoadCase& lc) -> std::optional<std::string> {
        const auto& value = access(lc);
        if (!value || std::find(users.begin(), users.end(), choice(lc)) == users.end()) return std::nullopt;
        return toml_number(*value);
      };
      key.default_words = needed_by;
      return key;
    };
    const auto law_number = [&](KeyDeclaration d, auto access, std::initializer_list<HardeningLaw> laws,
                                const char* needed_by) {
      return number_used_by(std::move(d), access, std::vector<HardeningLaw>(laws),
                            [](const LoadCase& lc) { return lc.material.hardening; }, needed_by);
    };
    {
      const auto K = [](auto& c) -> auto& { return c.material.K; };
      KeyDeclaration d = law_number({"material", "K", "number", "> 0", "Pa",
                                     "ludwik, swift: the strength coefficient K of sigma_y + K eps_p^n, K (prestrain + "
                                     "eps_p)^n"},
                                    K, {HardeningLaw::ludwik, HardeningLaw::swift}, "none: ludwik and swift need it");
      k.push_back(plausible(std::move(d), 1e5, 3e11, "the strength coefficients of solids", K));
    }
    k.push_back(law_number({"material", "prestrain", "number", "(0, 1)", "",
                            "swift: eps_0, the plastic strain the curve K (eps_0 + eps_p)^n starts from (the initial "
                            "yield stress is K eps_0^n)"},
                           [](auto& c) -> auto& { return c.material.prestrain; }, {HardeningLaw::swift},
                           "none: swift needs it"));
    {
      const auto Q = [](auto& c) -> auto& { return c.material.Q; };
      KeyDeclaration d = law_number({"material", "Q", "number", ">= 0", "Pa",
                                     "voce: the flow stress saturates at sigma_y + Q"},
                                    Q, {HardeningLaw::voce}, "none: voce needs it");
      k.push_back(std::move(d));
    }
    k.push_back(law_number({"material", "b", "number", "> 0", "",
                            "voce: the saturation rate b of sigma_y + Q (1 - exp(-b eps_p))"},
                           [](auto& c) -> auto& { return c.material.b; }, {HardeningLaw::voce}, "none: voce needs it"));
    {
      KeyDeclaration file{"material", "hardening_table", "string", "a CSV file of eps_p, sigma", "Pa",
                          "table: a tensile test's flow curve, rows eps_p, sigma from eps_p = 0 (sigma there is the "
                          "yield stress), eps_p increasing, sigma not falling; linear between rows; a header row may "
                          "lead; relative to the load case's folder"};
      file.read = [](const Reader& r, LoadCase& lc) {
        r.read_string("material", "hardening_table", lc.material.hardening_table_file);
      };
      file.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.material.hardening != HardeningLaw::table || lc.material.hardening_table_file.empty()) return std::nullopt;
        std::ostringstream text;
        text << toml::value<std::string>(lc.material.hardening_table_file);
        return text.str() + " read into hardening_points";
      };
      file.derived = true;  // case.toml holds the points themselves: a resumed run needs no file
      file.default_words = "none: table needs it or hardening_points";
      k.push_back(file);
    }
    {
      KeyDeclaration points{"material", "hardening_points", "array of [eps_p, sigma] pairs",
                            "as material.hardening_table", "Pa",
                            "table: the flow curve's points inline, instead of material.hardening_table (case.toml "
                            "writes them so)"};
      points.default_words = "none";
      points.plausible = KeyDeclaration::Plausible{1e5, 3e10, "the yield stresses of solids (the first point's sigma)"};
      points.magnitudes = [](const LoadCase& lc) -> std::vector<double> {
        if (lc.material.hardening != HardeningLaw::table || lc.material.hardening_points.empty()) return {};
        return {lc.material.hardening_points.front().second};
      };
      points.read = [](const Reader& r, LoadCase& lc) {
        r.read_points("material", "hardening_points", lc.material.hardening_points, "[eps_p, sigma]");
      };
      points.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.material.hardening != HardeningLaw::table) return std::nullopt;
        std::string text = "[";
        for (std::size_t i = 0; i < lc.material.hardening_points.size(); ++i)
          text += fmt::format("{}[{}, {}]", i ? ", " : "", toml_number(lc.material.hardening_points[i].first),
                              toml_number(lc.material.hardening_points[i].second));
        return text + "]";
      };
      k.push_back(points);
    }
    {
      KeyDeclaration extension = choice_key({"material", "table_extension", "choice", "", "",
                                             "table: beyond the last point flat (perfectly plastic) or along the last "
                                             "segment's slope (last_slope)"},
                                            table_extension_names,
                                            [](auto& c) -> auto& { return c.material.table_extension; });
      const auto write = extension.write;
      extension.write = [write](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.material.hardening != HardeningLaw::table) return std::nullopt;
        return write(lc);
      };
      extension.default_words = "flat";
      k.push_back(extension);
    }
    {
      KeyDeclaration measure = choice_key(
          {"material", "elastic_stress", "choice", "", "",
           "finite strain: the stress the elastic law's D : e sets, e the logarithmic elastic strain: cauchy "
           "(the true stress, as Abaqus's elasticity with NLGEOM and the field's reference simulations) or kirchhoff "
           "(tau = J sigma, Hencky's hyperelastic law); small strain refuses it"},
          elastic_stress_names, [](auto& c) -> auto& { return c.material.elastic_stress; });
      const auto write = measure.write;
      measure.write = [write](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.geometry.strain == StrainChoice::small) return std::nullopt;
        return write(lc);
      };
      measure.default_words = "cauchy";
      k.push_back(measure);
    }
    {
      KeyDeclaration rate = choice_key({"material", "rate", "choice", "", "",
                                        "j2's flow rule (docs/MODEL.md §13.3): none (rate-independent); perzyna "
                                        "(overstress: eps_p' = reference_strain_rate <sigma_e / sigma_y(eps_p) - "
                                        "1>^rate_exponent, on the hardening curve); norton (power-law creep: eps_p' = "
                                        "creep_coefficient (sigma_e / reference_stress)^rate_exponent, no yield "
                                        "surface, the hardening keys refused).  Both need load.times"},
                                       rate_law_names, [](auto& c) -> auto& { return c.material.rate; });
      // Written only when a rate is given: a rate-independent case's text (and a sweep's hash of
      // it) stays what it was before the key existed.
      const auto write = rate.write;
      rate.write = [write](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.material.rate == RateLaw::none) return std::nullopt;
        return write(lc);
      };
      rate.default_words = "none";
      k.push_back(rate);
    }
    // The flow rules' own parameters: written to case.toml only under their rule, required there
    // (validate_rate), refused under another.
    const auto rule_number = [&](KeyDeclaration d, auto access, std::initializer_list<RateLaw> rules,
                                 const char* needed_by) {
      return number_used_by(std::move(d), access, std::vector<RateLaw>(rules),
                            [](const LoadCase& lc) { return lc.material.rate; }, needed_by);
    };
    k.push_back(rule_number({"material", "reference_strain_rate", "number", "> 0", "1/s",
                             "perzyna: the strain rate rate0 of eps_p' = rate0 <sigma_e / sigma_y - 1>^m (rate0 -> "
                             "infinity is rate-independent j2)"},
                            [](auto& c) -> auto& { return c.material.reference_strain_rate; }, {RateLaw::perzyna},
                            "none: perzyna needs it"));
    k.push_back(rule_number({"material", "creep_coefficient", "number", "> 0", "1/s",
                             "norton: A of eps_p' = A (sigma_e / reference_stress)^m, the creep rate at the "
                             "reference stress"},
                            [](auto& c) -> auto& { return c.material.creep_coefficient; }, {RateLaw::norton},
                            "none: norton needs it"));
    {
      const auto reference = [](auto& c) -> auto& { return c.material.reference_stress; };
      k.push_back(plausible(rule_number({"material", "reference_stress", "number", "> 0", "Pa",
                                         "norton: sigma_ref of eps_p' = A (sigma_e / sigma_ref)^m"},
                                        reference, {RateLaw::norton}, "none: norton needs it"),
                            1e3, 3e10, "the stresses of solids", reference));
    }
    k.push_back(rule_number({"material", "rate_exponent", "number", "[1, 100]", "",
                             "perzyna, norton: the exponent m of the flow rule (1: linear viscosity; metals creep "
                             "with m = 3 to 8; 1/m is the strain-rate sensitivity)"},
                            [](auto& c) -> auto& { return c.material.rate_exponent; },
                            {RateLaw::perzyna, RateLaw::norton}, "none: perzyna and norton need it"));
    {
      KeyDeclaration control = choice_key({"load", "control", "choice", "", "",
                                           "what load.path steps: depth (the force is the result) or force (the "
                                           "depth is solved for with each increment; docs/MODEL.md §13.1)"},
                                          load_control_names, [](auto& c) -> auto& { return c.load.control; });
      // Written only when it is "force": a depth-controlled case's text (and a sweep's hash of it)
      // stays what it was before the key existed.
      const auto write = control.write;
      control.write = [write](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.load.control == LoadControlKind::depth) return std::nullopt;
        return write(lc);
      };
      control.default_words = "\"depth\"";
      k.push_back(control);
    }
    {
      const auto path = [](auto& c) -> auto& { return c.load.path; };
      KeyDeclaration d = numbers_key({"load", "path", "array of numbers", "from 0, each >= 0", "m or N",
                                      "waypoints of load.control's quantity, piecewise linear: depths h [m], or "
                                      "forces P [N; N/m in plane strain]; may go down (unload, separate) and up again",
                                      true},
                                     path);
      d.plausible = KeyDeclaration::Plausible{1e-10, 0.1, "indentation depths (the deepest waypoint)"};
      // Forces span nano- to macro-indentation (1e-9 N to 1e4 N, per metre in plane strain): no
      // magnitude tells a slip there.
      d.magnitudes = [](const LoadCase& lc) -> std::vector<double> {
        if (lc.load.path.empty() || lc.load.control == LoadControlKind::force) return {};
        return {lc.load.largest_target()};
      };
      k.push_back(d);
    }
    {
      KeyDeclaration times = numbers_key(
          {"load", "times", "array of numbers", "from 0, increasing; one per load.path waypoint", "s",
           "the time at each waypoint of load.path (docs/MODEL.md §13.2): the path as a protocol in time, a "
           "repeated waypoint a hold; increments are spread by duration and curve.csv gains a time column"},
          [](auto& c) -> auto& { return c.load.times; });
      // Written only when given: a case without time reads and hashes as before the key existed.
      const auto write = times.write;
      times.write = [write](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.load.times.empty()) return std::nullopt;
        return write(lc);
      };
      times.default_words = "none: the path has no time";
      k.push_back(times);
    }
    {
      KeyDeclaration estimate = optional_number_key(
          {"load", "depth_estimate", "number", "> 0", "m",
           "force control: the depth the largest force reaches, which sizes the mesh (written by case.toml from "
           "the depth pilot; given, the run needs no pilot)"},
          [](auto& c) -> auto& { return c.load.depth_estimate; });
      estimate.default_words = "none: measured by the depth pilot";
      k.push_back(estimate);
    }
    {
      KeyDeclaration inc{"load", "increments", "integer or array of integers", "[1, 1e7] in all", "",
                         "increments along the whole path (spread by path length, or by duration with load.times), or one "
                         "count per segment",
                         true};
      inc.read = [](const Reader& r, LoadCase& lc) { r.read_increments(lc.load); };
      inc.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.load.segment_increments.empty()) return std::to_string(lc.load.increments);
        std::string text = "[";
        for (std::size_t i = 0; i < lc.load.segment_increments.size(); ++i)
          text += fmt::format("{}{}", i ? ", " : "", lc.load.segment_increments[i]);
        return text + "]";
      };
      k.push_back(inc);
    }
    k.push_back(choice_key({"mesh", "element", "choice", "", "",
                            "q1 (the paper's exact element), bbar (mean dilatation, locking-free), auto (B-bar when "
                            "nu >= 0.45 or kappa > 0.95 or n < 0.1 or a j2 flow curve (power_law ... table), or a plastic material "
                            "under a cone or an area function)"},
                           element_names, [](auto& c) -> auto& { return c.mesh.element; }));
    k.push_back(integer_key({"mesh", "contact_nodes", "integer", ">= 2", "",
                             "fine-zone elements across the estimated final contact half-width (raise it to buy "
                             "accuracy); 30 under a cone or an area function"},
                            [](auto& c) -> auto& { return c.mesh.contact_nodes; }));
    k.push_back(plausible(optional_number_key({"mesh", "contact_half_width", "number", "> 0", "m",
                                     "override of the estimate a* that sizes the mesh (default: Hertz, or a pilot run)"},
                                    [](auto& c) -> auto& { return c.mesh.contact_half_width; }), 1e-10, 10.0, "the lengths of a mesh", [](auto& c) -> auto& { return c.mesh.contact_half_width; }));
    k.push_back(plausible(optional_number_key({"mesh", "fine_width", "number", "> 0", "m", "override: width of the uniform zone (default 1.5 a*)"},
                                    [](auto& c) -> auto& { return c.mesh.fine_width; }), 1e-10, 10.0, "the lengths of a mesh", [](auto& c) -> auto& { return c.mesh.fine_width; }));
    k.push_back(plausible(optional_number_key({"mesh", "fine_depth", "number", "> 0", "m", "override: depth of the uniform zone (default 1.5 a*)"},
                                    [](auto& c) -> auto& { return c.mesh.fine_depth; }), 1e-10, 10.0, "the lengths of a mesh", [](auto& c) -> auto& { return c.mesh.fine_depth; }));
    k.push_back(optional_number_key({"mesh", "growth", "number", "[1, 2]", "",
                                     "override: growth ratio of the far field (default 1 + 2.5 / contact_nodes)"},
                                    [](auto& c) -> auto& { return c.mesh.growth; }));
    {
      KeyDeclaration zone{"mesh", "plastic_zone", "array of [h, width, depth] triples", "depths increasing, >= 0", "m",
                          "written by case.toml: the pilot run's plastic zone as it grew with the depth h (sizes the "
                          "condensed near field); with contact_half_width, the run needs no pilot"};
      zone.default_words = "none: measured by the pilot";
      zone.read = [](const Reader& r, LoadCase& lc) { r.read_tuples("mesh", "plastic_zone", "[h, width, depth] triples", "a triple [h, width, depth]",
                      lc.mesh.plastic_zone); };
      zone.write = [](const LoadCase& lc) -> std::optional<std::string> {
        if (lc.mesh.plastic_zone.empty()) return std::nullopt;
        std::string text = "[";
        for (std::size_t i = 0; i < lc.mesh.plastic_zone.size(); ++i) {
          const auto& z = lc.mesh.plastic_zone[i];
          text += fmt::format("{}[{}, {}, {}]", i ? ", " : "", toml_number(z[0]), toml_number(z[1]), toml_number(z[2]));
        }
        return text + "]";
      };
      k.push_back(zone);
    }
    k.push_back(integer_key({"mesh", "max_unknowns", "integer", "[1000, 2000000000]", "",
                             "the largest mesh the case may plan, in unknowns (the planned mesh and its companion "
                             "runs are refused beyond it, before any work; raise it for a mesh meant to be larger)"},
                            [](auto& c) -> auto& { return c.mesh.max_unknowns; }));
    k.push_back(choice_key({"mesh", "error_estimate", "choice", "", "",
                            "richardson: a companion run at half the contact_nodes gives each increment's "
                            "discretization error of P and a (curve.csv, summary.json); observed: a second one at "
                            "a quarter measures the order; off"},
                           error_estimate_names, [](auto& c) -> auto& { return c.mesh.error_estimate; }));
    k.push_back(optional_number_key({"mesh", "target_error", "number", "[1e-5, 0.1]", "",
                                     "relative error of the final P asked for: pilots choose contact_nodes (and, for a "
                                     "run that depends on its increments, the increments); the run checks its "
                                     "estimates and refines once if it missed"},
                                    [](auto& c) -> auto& { return c.mesh.target_error; }));
    {
      KeyDeclaration dir{"output", "dir", "string", "not empty", "",
                         "output folder (relative to the working directory); by default out/ and the case file's "
                         "name without its extension, so that runs of different cases keep their own folders"};
      dir.default_words = "out/<case name>";
      dir.read = [](const Reader& r, LoadCase& lc) { r.read_string("output", "dir", lc.output.dir); };
      dir.write = [](const LoadCase& lc) -> std::optional<std::string> {
        std::ostringstream text;
        text << toml::value<std::string>(lc.output.dir);
        return text.str();
      };
      k.push_back(dir);
    }
    k.push_back(integer_key({"output", "fields_every", "integer", ">= 0", "",
                             "write a VTU every N increments (0: the final state only)"},
                            [](auto& c) -> auto& { return c.output.fields_every; }));
    k.push_back(numbers_key({"output", "profile_depths", "array of numbers", "within [0, ly]", "m",
                             "depths of the stress profiles besides the surface"},
                            [](auto& c) -> auto& { return c.output.profile_depths; }));
    k.push_back(integer_key({"output", "checkpoint_every", "integer", ">= 0", "",
                             "checkpoint at increments numbered a multiple of N, at every peak and valley and at the "
                             "end (0: reversals and signals only)"},
                            [](auto& c) -> auto& { return c.output.checkpoint_every; }));
    {
      KeyDeclaration keep{"output", "keep_checkpoints", "integer or \"all\"", ">= 1", "",
                          "newest checkpoints kept; every peak's and valley's are kept besides"};
      keep.read = [](const Reader& r, LoadCase& lc) { r.read_count_or_all("output", "keep_checkpoints", lc.output.keep_checkpoints); };
      keep.write = [](const LoadCase& lc) -> std::optional<std::string> {
        return lc.output.keep_checkpoints == 0 ? std::string("\"all\"") : std::to_string(lc.output.keep_checkpoints);
      };
      k.push_back(keep);
    }
    k.push_back(numbers_key({"analysis", "fit_range", "array of two numbers", "0 <= lower < upper <= 1", "",
                             "the unloading fit P = B (h - h_f)^m uses the points with lower P_max <= P <= upper "
                             "P_max (ISO 14577 practice: 20% to 98%)"},
                            [](auto& c) -> auto& { return c.analysis.fit_range; }));
    k.push_back(optional_number_key({"analysis", "epsilon", "number", "(0, 1]", "",
                                     "h_c = h_max - epsilon P_max / S (default 0.75 sphere, profile and area function, "
                                     "0.72 cone, 1 flat)"},
                                    [](auto& c) -> auto& { return c.analysis.epsilon; }));
    k.push_back(number_key({"analysis", "beta", "number", "[1, 1.2]", "",
                            "E_r = sqrt(pi) / (2 beta) S / sqrt(A_c) (1 for a body of revolution, 1.034 for a "
                            "Berkovich pyramid)"},
                           [](auto& c) -> auto& { return c.analysis.beta; }));
    k.push_back(plausible(optional_number_key({"analysis", "indenter_E", "number", "> 0", "Pa",
                                     "the indenter's Young's modulus for the specimen modulus (default: rigid; "
                                     "diamond 1141e9)"},
                                    [](auto& c) -> auto& { return c.analysis.indenter_E; }), 1e3, 2e12, "the moduli of solids", [](auto& c) -> auto& { return c.analysis.indenter_E; }));
    k.push_back(number_key({"analysis", "indenter_nu", "number", "(-1, 0.5)", "", "the indenter's Poisson's ratio"},
                           [](auto& c) -> auto& { return c.analysis.indenter_nu; }));
    k.push_back(number_key({"analysis", "substrate_tolerance", "number", "(0, 1)", "",
                            "a coated run's `analyze` warns where the substrate moves E_r or H by more than this "
                            "fraction from the film's own (a companion run of the film alone; docs/MODEL.md §14.4)"},
                           [](auto& c) -> auto& { return c.analysis.substrate_tolerance; }));
    k.push_back(number_key({"solver", "tolerance", "number", "[1e-14, 1e-2)", "",
                            "residual max-norm relative to E* times the deepest depth (times 2 pi a* in axisymmetry: ring forces)"},
                           [](auto& c) -> auto& { return c.solver.tolerance; },
                           // The residual is relative to E* alpha_max; round-off in assembling it is about
                           // 1e-16 times the condition of the stiffness: below 1e-14 it is only run into.
                           ": below 1e-14 round-off dominates the residual"));
    k.push_back(integer_key({"solver", "max_newton", "integer", "[1, 1000]", "", "Newton iterations per attempt"},
                            [](auto& c) -> auto& { return c.solver.max_newton; }));
    k.push_back(integer_key({"solver", "max_cutbacks", "integer", "[0, 60]", "", "halvings of one increment before the run stops"},
                            [](auto& c) -> auto& { return c.solver.max_cutbacks; }));
    k.push_back(choice_key({"solver", "linear", "choice", "", "",
                            "klu (SuiteSparse KLU), cholmod (supernodal Cholesky), auto (CHOLMOD from 1000 unknowns "
                            "of the run's largest Newton system, chosen once per run)"},
                           linear_names, [](auto& c) -> auto& { return c.solver.linear; }));
    k.push_back(choice_key({"solver", "far_field", "choice", "", "",
                            "condense (Newton solves the near field, the elastic far field condensed exactly), full "
                            "(the whole mesh), auto (condense unless the near field is over 80% of the unknowns)"},
                           far_field_names, [](auto& c) -> auto& { return c.solver.far_field; }));
    k.push_back(choice_key({"solver", "jacobian", "choice", "", "",
                            "how a Newton iteration solves its linear system: krylov (GMRES preconditioned by a "
                            "factorization kept across the iterations), reuse (a factorization per iteration; a "
                            "converging one may keep the last), fresh (factor every iteration), auto (krylov for a "
                            "plastic specimen or finite strain, reuse for an elastic one in small strain)"},
                           jacobian_names, [](auto& c) -> auto& { return c.solver.jacobian; }));
    k.push_back(choice_key({"contact", "discretization", "choice", "", "",
                            "node_to_rigid (a complementarity row per surface node, the seed paper's), "
                            "integrated_gap (the penetration integrated over the surface against the exact punch "
                            "profile, a penalty pressure: the contact edge moves inside the elements)"},
                           contact_discretization_names,
                           [](auto& c) -> auto& { return c.contact.discretization; }));
    k.push_back(number_key({"contact", "penalty", "number", "[1, 1e6]", "",
                            "integrated_gap's penalty over a surface node's own stiffness: the penetration under a "
                            "pressure p is about p h / (penalty E*)"},
                           [](auto& c) -> auto& { return c.contact.penalty; }));
    {
      KeyDeclaration friction{"contact", "friction", "number or \"sticking\"", ">= 0", "",
                              "Coulomb's friction coefficient mu between specimen and punch (0: frictionless; "
                              "\"sticking\": no slip once in contact); node_to_rigid only, KLU only unless sticking"};
      friction.read = [](const Reader& r, LoadCase& lc) {
        r.read_number_or_word("contact", "friction", "sticking", std::numeric_limits<double>::infinity(),
                              lc.contact.friction);
      };
      friction.write = [](const LoadCase& lc) -> std::optional<std::string> {
        return std::isinf(lc.contact.friction) ? std::string("\"sticking\"") : toml_number(lc.contact.friction);
      };
      // ">= 0" with "sticking" read as +infinity, which a one-sided interval's check would refuse.
      friction.check = [](const LoadCase& lc) {
        if (!(lc.contact.friction >= 0.0))
          throw InputError(lc.source, "contact.friction", fmt::format("must be >= 0 (got {})", lc.contact.friction));
      };
      k.push_back(friction);
    }
    return k;
  }();
  return keys;
}

}  // namespace input_detail

using namespace input_detail;

std::string toml_number(double value) {
  std::string text = fmt::format("{}", value);
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";  // "15" would read as an integer
  return text;
}

std::string toml_string(const std::string& s) {
  std::string quoted = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') quoted += std::string("\\") + c;
    else if (c == '\n') quoted += "\\n";
    else if (c == '\t') quoted += "\\t";
    else if (c == '\r') quoted += "\\r";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) quoted += fmt::format("\\u{:04X}", static_cast<unsigned char>(c));
    else quoted += c;
  }
  return quoted + "\"";
}

std::string to_toml(const LoadCase& lc) {
  std::string t = fmt::format("# The load case as run (from {}), every key explicit.\n# Written by {}.\n",
                              printable(lc.source, 400), version_line());
  std::string section;
  for (const auto& key : key_declarations()) {
    if (section != key.section) {
      t += fmt::format("{}[{}]\n", section.empty() ? "" : "\n", key.section);
      section = key.section;
    }
    const std::optional<std::string> value = key.write(lc);
    if (!value) continue;
    if (key.derived) t += fmt::format("# {} = {}  ({}: derived, shown for reference)\n", key.name, *value, key.unit);
    else t += fmt::format("{} = {}\n", key.name, *value);
  }
  // The layers from the surface down, each material written by the [material] declarations.
  for (const LayerInput& layer : lc.layers) {
    t += fmt::format("\n[[layer]]\nthickness = {}\n[layer.material]\n", toml_number(layer.thickness));
    const LoadCase scratch = with_material(lc, layer.material);
    for (const auto& key : key_declarations()) {
      if (std::string(key.section) != "material") continue;
      const std::optional<std::string> value = key.write(scratch);
      if (!value) continue;
      if (key.derived) t += fmt::format("# {} = {}  ({}: derived, shown for reference)\n", key.name, *value, key.unit);
      else t += fmt::format("{} = {}\n", key.name, *value);
    }
  }
  return t;
}

std::string keys_markdown() {
  std::string t = "| key | type | default | accepted | unit | meaning |\n|---|---|---|---|---|---|\n";
  for (const auto& k : describe_keys()) {
    const auto cell = [](std::string text) {
      std::string out;
      for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
      return out;
    };
    t += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", k.key, cell(k.type),
                     k.required ? "required" : "`" + cell(k.default_value) + "`", cell(k.range), k.unit.empty() ? "" : k.unit,
                     cell(k.help));
  }
  return t;
}

std::vector<KeyDescription> describe_keys() {
  const LoadCase defaults;
  std::vector<KeyDescription> out;
  const auto& declarations = key_declarations();
  for (std::size_t i = 0; i < declarations.size(); ++i) {
    const auto& key = declarations[i];
    // The [[layer]] tables follow [material], whose keys each layer's material takes.
    if (i > 0 && std::string(declarations[i - 1].section) == "material" && std::string(key.section) != "material") {
      out.push_back({"layer.thickness", "number", "required", ">= 1e-9 geometry.ly, the layers' sum < geometry.ly", "m",
                     "[[layer]], one per layer from the surface down (docs/MODEL.md §14): the layer's thickness; the "
                     "layers lie on the substrate [material] describes",
                     true, false});
      out.push_back({"layer.material.KEY", "table", "required", "every key of [material], checked as there", "",
                     "[layer.material]: the layer's material, perfectly bonded to its neighbours; addressed as "
                     "layer.K.material.KEY (K from 1 at the surface) by --set, sweeps and fit --free",
                     true, false});
    }
    KeyDescription d;
    d.key = std::string(key.section) + "." + key.name;
    d.type = key.type;
    d.range = key.range;
    d.unit = key.unit;
    d.help = key.help;
    d.required = key.required;
    if (key.required) d.default_value = "required";
    else if (key.default_words) d.default_value = key.default_words;
    else d.default_value = key.write(defaults).value_or("(computed)");
    d.default_is_value = !key.required && !key.default_words && key.write(defaults).has_value();
    out.push_back(d);
  }
  return out;
}

std::vector<std::string> implausible_values(const LoadCase& lc) {
  std::vector<std::string> warnings;
  // Each layer's material is checked as [material] is, named as the layer's.
  for (std::size_t k = 0; k < lc.layers.size(); ++k)
    for (const std::string& w : implausible_values(with_material(lc, lc.layers[k].material)))
      if (w.rfind("material.", 0) == 0) warnings.push_back(fmt::format("layer[{}].{}", k + 1, w));
  for (const auto& key : key_declarations()) {
    if (!key.plausible || !key.magnitudes) continue;
    const auto& p = *key.plausible;
    for (const double v : key.magnitudes(lc)) {
      if (!(std::abs(v) < p.low || std::abs(v) > p.high)) continue;
      const std::string unit = key.unit;
      const std::string hint = unit == "m"         ? "metres are meant (2 um is 2e-6)"
                               : unit == "Pa"      ? "pascals are meant (300 MPa is 300e6, 210 GPa is 210e9)"
                               : unit == "degrees" ? "degrees between axis and face are meant (70.3 for the "
                                                     "Berkovich-equivalent cone)"
                                                   : "is the unit right?";
      warnings.push_back(fmt::format("{}.{} = {:g} {} lies outside {} ({:g} to {:g} {}): {}", key.section, key.name, v,
                                     unit, p.of_what, p.low, p.high, unit, hint));
    }
  }
  return warnings;
}

std::optional<std::string> declared_interval_problem(const std::string& key, double value) {
  for (const auto& k : key_declarations()) {
    if (key != std::string(k.section) + "." + k.name) continue;
    const auto bounds = bounds_of(k.range);
    return bounds ? bounds->problem(value) : std::nullopt;
  }
  return std::nullopt;
}

std::optional<PlausibleMagnitudes> plausible_magnitudes(const std::string& key) {
  for (const auto& k : key_declarations())
    if (key == std::string(k.section) + "." + k.name && k.plausible)
      return PlausibleMagnitudes{k.plausible->low, k.plausible->high, k.plausible->of_what};
  return std::nullopt;
}

std::string first_physics_difference(const LoadCase& a, const LoadCase& b) {
  for (const auto& key : key_declarations()) {
    const std::string section = key.section;
    if (section != "geometry" && section != "punch" && section != "material" && section != "mesh" &&
        section != "contact")
      continue;
    if (key.derived) continue;
    if (key.write(a) != key.write(b)) return section + "." + key.name;
  }
  if (a.layers.size() != b.layers.size()) return "layer";
  for (std::size_t k = 0; k < a.layers.size(); ++k) {
    const std::string name = fmt::format("layer[{}]", k + 1);
    if (toml_number(a.layers[k].thickness) != toml_number(b.layers[k].thickness)) return name + ".thickness";
    const LoadCase la = with_material(a, a.layers[k].material), lb = with_material(b, b.layers[k].material);
    for (const auto& key : key_declarations())
      if (std::string(key.section) == "material" && !key.derived && key.write(la) != key.write(lb))
        return name + ".material." + key.name;
  }
  return "";
}

}  // namespace indentsim
