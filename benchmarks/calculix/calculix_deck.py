"""CalculiX 2.20 decks of indentsim's scenes, node for node on indentsim's own mesh.

The deck is built from an indentsim run folder: its `case.toml` (every key explicit), the depths of
its `curve.csv`, the grid of its `fields/step_000000.vtu` and, for the contact, the nodes'
`contact_status` and displacements in the fields of every increment.  Both codes then have the
same discrete problem, so their forces must agree to the solvers' tolerances on any mesh; what
differs is only the implementation (elements, constitutive update, equilibrium iterations) and
what expected_difference bounds.

  * elements: CPE4 (plane strain, one length unit thick) or CAX4 (axisymmetric: x = r, y = z),
    bilinear with full 2x2 integration -- indentsim's Q1 (run it with mesh.element = "q1");
  * the base fixed, the axis x = 0 held in x, the far side free (MODEL.md);
  * material: elastic, or J2 flow theory with isotropic hardening (*PLASTIC).  indentsim's J2 law
    takes its hardening curve from the Ilyushin law of the same parameters: on a proportional path
    the equivalent plastic strain is eps_p = e_u omega(e_u) and the yield stress
    sigma_u = 3 mu (1 - omega(e_u)) e_u (include/indentsim/materials/material.hpp).  The linear law is two
    points of ccx's table (exact); the power law is tabulated (hardening_table).  Ilyushin's
    deformation theory has no counterpart in ccx;
  * a coated specimen ([[layer]] tables, from the surface down, over the substrate [material]): one
    element set and one material per region, numbered as indentsim numbers them (0 the substrate:
    EBLOCK, SPECIMEN; layer k: ELAYERk, LAYERk), each written as a homogeneous specimen's is.  A
    row of elements belongs to layer k where its centroid's depth lies strictly inside the band
    between the layers' cumulative thicknesses above and below layer k, to the substrate below
    them; indentsim lays each interface on a mesh line, so no element straddles one (checked, and
    checked against the `region` of indentsim's fields);
  * the punch profile g(x) of MODEL.md is written out here again (sphere, cone with or without a
    spherical tip, flat), independently of src/geometry/punch.cpp.
Three ways to impose the contact (`contact`):
  * "replay" (every scene): one ccx *STEP per indentsim increment (*STATIC, DIRECT: one increment,
    so J2's backward-Euler update sees the same strain increments in both codes), every node's
    displacement prescribed to indentsim's.  ccx updates its stresses along that strain path and
    prints its element forces: they must vanish at indentsim's unknowns (replay_residual), they
    are the reactions at the contact nodes, and with indentsim's surface they must satisfy the
    Signorini conditions (check_signorini);
  * "given" (elastic scenes): the same steps, with only the nodes indentsim found in contact
    prescribed to the punch, u_y = -alpha_k + g(x) (*BOUNDARY, OP=NEW), and ccx solving for the
    rest.  On plastic scenes ccx's Newton iterations stall or cycle between two states;
  * "gap" (elastic scenes): ccx finds the contact itself, one GAPUNI element from each surface
    node within reach to one rigid punch node driven through the run's depths, direction
    (0, 1, 0), clearance g(x): exactly the vertical-gap condition.  On plastic scenes ccx did not
    converge with gap elements (fixed increments with gap stiffnesses 1e4 to 1e9 E h, automatic
    increments at 1e9 E h).
CalculiX pitfalls met on the way:
  * numbers on data lines are read in 20-character fields: 13 significant digits fit;
  * elements whose Jacobian determinant is below an absolute threshold are refused ("nonpositive
    jacobian"): a Berkovich cone's 0.3 mm specimen, expanded into a 2-degree wedge, is, in metres.
    The deck's unit of length is the specimen's height (length_unit);
  * GAPUNI elements alone do not make a *STATIC step nonlinear: ccx solves once, linearly, and
    the contact is wrong.  A *PLASTIC material that no element uses switches on its Newton
    iterations (small strains, no NLGEOM);
  * the clearance belongs to the *GAP card, so every gap element gets its own element set;
  * an open GAPUNI still pulls, with a force rising to f_inf (the *GAP card's 7th value, 1e-3 N by
    default) as it opens: on an axisymmetric wedge that was 40% of the first increment's force;
  * the gap stiffness is a penalty: 1e4 E h (h the finest element) left the paper's P 7% low, and
    1e9 E h leaves it unchanged to the printed digits;
  * an axisymmetric model is expanded into a 2-degree wedge of straight-sided hexahedra: its
    forces are those of the wedge, so the whole ring's force is 180 times the printed one; the
    wedge's geometry differs from the exact ring's by O(1 degree^2) (with "given" and "gap", ccx's
    P on the elastic scenes is 2.5-2.8e-5 below indentsim's at every increment, whatever the gap
    stiffness; 5.5e-5 above it with a 400 GPa film on a 100 GPa substrate, whose displacements the
    exact ring's Q1 forces balance to 4e-12 of the largest contact reaction); and the radial force
    it prints at a node is not that node's radial residual;
  * ccx's stress update went wrong with power-law tables of 200 points or more: P moved 3.8e-3 away
    from the limit that tables of 40, 60, 100 and 120 points converge to (as the square of their
    log step), and ccx ran nine times slower.  Tables of 100 points;
  * ccx's default convergence test is on the residual relative to the average force
    (R_alpha^n = 0.005): tightened here (*CONTROLS) for the given contact set;
  * the .dat file prints 7 significant digits, so ccx's P is known to about 2.5e-7.
"""

import base64
import math
import os
import re
import subprocess
import time
import tomllib
import xml.etree.ElementTree as ET

import numpy as np


class DeckError(Exception):
    """A scene this deck builder does not cover, or a ccx failure; the message says which."""


# ---------------------------------------------------------------------------------------------
# The run folder


def point_arrays(vtu):
    """{name: array} of a VTU's point data and its point coordinates (indentsim's binary VTU:
    base64 with a UInt64 byte count in front)."""
    piece = ET.parse(vtu).getroot().find("UnstructuredGrid").find("Piece")
    dtypes = {"Float64": "<f8", "Int32": "<i4"}

    def decode(array):
        raw = base64.b64decode("".join(array.text.split()))
        size = int.from_bytes(raw[:8], "little")
        values = np.frombuffer(raw[8:8 + size], dtype=dtypes[array.get("type")])
        components = int(array.get("NumberOfComponents", "1"))
        return values.reshape(-1, components) if components > 1 else values

    arrays = {a.get("Name"): decode(a) for a in piece.find("PointData").findall("DataArray")}
    arrays["coordinates"] = decode(next(a for a in piece.find("Points").findall("DataArray")
                                        if a.get("Name") == "coordinates"))
    return arrays


def cell_regions(vtu, ys):
    """The `region` cell array of a VTU (0 the substrate, k layer k from the surface) as one region per
    row of elements, j = 0 at the base; None where the VTU has none (a homogeneous run, or an
    indentsim from before the layers).  A row with two regions is returned as -1: no deck matches it."""
    piece = ET.parse(vtu).getroot().find("UnstructuredGrid").find("Piece")
    dtypes = {"Float64": "<f8", "Int32": "<i4", "Int64": "<i8"}

    def decode(array):
        raw = base64.b64decode("".join(array.text.split()))
        size = int.from_bytes(raw[:8], "little")
        return np.frombuffer(raw[8:8 + size], dtype=dtypes[array.get("type")])

    region = next((a for a in piece.find("CellData").findall("DataArray") if a.get("Name") == "region"), None)
    if region is None:
        return None
    cells = {a.get("Name"): a for a in piece.find("Cells").findall("DataArray")}
    connectivity, offsets = decode(cells["connectivity"]), decode(cells["offsets"])
    y = point_arrays(vtu)["coordinates"][:, 1]
    starts = np.concatenate(([0], offsets[:-1]))
    # A cell's row: where its lowest node lies among the grid's rows (cells in any order).
    rows = np.searchsorted(ys, [np.min(y[connectivity[a:b]]) for a, b in zip(starts, offsets)])
    by_row = np.full(len(ys) - 1, -2)
    for j, r in zip(rows, decode(region)):
        by_row[j] = r if by_row[j] in (-2, r) else -1
    return by_row


def read_run(run_dir):
    """The scene of an indentsim run folder: its load case, depths, forces, grid and, where the
    fields of every increment were written, the surface nodes in contact at each; for a coated
    specimen also the region of each row of elements as indentsim's fields give it."""
    with open(run_dir / "case.toml", "rb") as f:
        case = tomllib.load(f)
    with open(run_dir / "curve.csv") as f:
        header = f.readline().strip().split(",")
        rows = [line.split(",") for line in f.read().strip().splitlines()]
    column = {name: [float(r[header.index(name)]) for r in rows]
              for name in ("alpha", "P", "a", "cutbacks", "max_strain_intensity")}
    if any(column["cutbacks"]):
        raise DeckError(f"{run_dir}: the run cut increments back; ccx would step differently (J2 is path dependent)")
    first = point_arrays(run_dir / "fields" / "step_000000.vtu")
    points = first["coordinates"]
    xs, ys = np.unique(points[:, 0]), np.unique(points[:, 1])
    if len(xs) * len(ys) != len(points):
        raise DeckError(f"{run_dir}: the mesh is not a tensor-product grid")
    # The deck numbers node (i, j) -- i along x, j up from the base -- as j nx + i + 1; `order`
    # lists indentsim's point index for each, wherever indentsim puts it in its own numbering.
    x_index, row = np.searchsorted(xs, points[:, 0]), np.searchsorted(ys, points[:, 1])
    order = np.empty(len(points), dtype=int)
    order[row * len(xs) + x_index] = np.arange(len(points))
    top = order[(len(ys) - 1) * len(xs):]
    contact_sets, displacements = [], []
    for k in range(len(rows)):
        vtu = run_dir / "fields" / f"step_{k:06d}.vtu"
        if k > 0 and not vtu.exists():
            contact_sets = displacements = None
            break
        arrays = first if k == 0 else point_arrays(vtu)
        # contact_status: 1 in contact, 0 an open candidate, -1 no candidate.
        contact_sets.append([i for i in range(len(xs)) if arrays["contact_status"][top[i]] == 1])
        displacements.append(arrays["displacement"][order, :2])
    return dict(case=case, kind=case["geometry"]["kind"], alphas=column["alpha"], forces=column["P"],
                half_widths=column["a"], largest_strain_intensity=max(column["max_strain_intensity"]), xs=xs, ys=ys,
                contact_sets=contact_sets, displacements=displacements,
                fields_regions=cell_regions(run_dir / "fields" / "step_000000.vtu", ys))


# ---------------------------------------------------------------------------------------------
# The scene's physics, written out again from MODEL.md


def punch_gap(punch):
    """g(x) of MODEL.md ('Punch and contact', the axisymmetric profiles) and the largest x where the
    punch has a surface."""
    shape = punch["shape"]
    if shape == "sphere":
        radius = punch["radius"]
        return (lambda x: x * x / (radius + math.sqrt((radius - x) * (radius + x)))), 0.999 * radius
    if shape == "cone":
        theta = math.radians(punch["half_angle"])
        tip = punch.get("tip_radius", 0.0)
        cap = tip * math.cos(theta)  # where the tip sphere's slope equals the face's, cot(theta)
        cap_height = tip - math.sqrt(tip * tip - cap * cap)

        def cone(x):
            if x < cap:
                return x * x / (tip + math.sqrt((tip - x) * (tip + x)))
            return cap_height + (x - cap) / math.tan(theta)

        return cone, math.inf
    if shape == "flat":
        return (lambda x: 0.0), punch["radius"] * (1.0 + 1e-12)
    raise DeckError(f"punch.shape = \"{shape}\": only sphere, cone and flat are built here")


def region_materials(case):
    """The specimen's materials by region, numbered as indentsim numbers them: [(key, material)], 0 the
    substrate ([material]), k the k-th [[layer]] from the surface ([layer.material]); key names the
    table as indentsim's own messages do."""
    return [("material", case["material"])] + [(f"layer[{k}].material", layer["material"])
                                               for k, layer in enumerate(case.get("layer", []), 1)]


def check_material(key, material):
    """Refuses a material this deck cannot write as ccx's (DeckError naming key, the region's table)."""
    if material["model"] not in ("elastic", "j2"):
        raise DeckError(f"{key}.model = \"{material['model']}\": ccx has no Ilyushin (deformation) law; "
                        "compare with model = \"j2\"")
    if material["model"] == "elastic":
        return
    # hardening_table writes out only the Ilyushin-derived linear and power curves; another law
    # would be tabulated as the power law of its n, silently.
    if material["hardening"] not in ("linear", "power"):
        raise DeckError(f"{key}.hardening = \"{material['hardening']}\": only the linear and power laws are "
                        "tabulated here (hardening_table)")
    # ccx's *PLASTIC is rate-independent: a flow rule (written to case.toml only when given) would
    # differ at every increment.
    if material.get("rate", "none") != "none":
        raise DeckError(f"{key}.rate = \"{material['rate']}\": ccx's *PLASTIC has no flow rule")


def row_regions(scene):
    """The region of each row of elements (j = 0 at the base), as indentsim numbers them: layer k where
    the depth of the row's centroid lies strictly inside layer k's band (between the layers'
    cumulative thicknesses above it and down to it), the substrate below the last layer.  In the
    tensor-product grid every element of a row has the row's centroid depth."""
    ys = scene["ys"]
    bottoms = np.cumsum([layer["thickness"] for layer in scene["case"].get("layer", [])])
    for k, bottom in enumerate(bottoms, 1):
        # indentsim lays each interface on a row of nodes; off one, a row of elements would have two
        # materials, which neither code has.
        if np.min(np.abs(ys[-1] - ys - bottom)) > 1e-9 * (ys[-1] - ys[0]):
            raise DeckError(f"layer[{k}]'s bottom, {bottom:g} m below the surface, is on no row of nodes")
    depths = ys[-1] - 0.5 * (ys[:-1] + ys[1:])
    regions = np.zeros(len(depths), dtype=int)
    for k, (top, bottom) in enumerate(zip(np.concatenate(([0.0], bottoms[:-1])), bottoms), 1):
        regions[(depths > top) & (depths < bottom)] = k
    # The regions indentsim says it used (its fields' `region`), where it wrote them: the deck's
    # reading of the layers' depths must be indentsim's, or the two codes solve different problems.
    fields = scene.get("fields_regions")
    if fields is not None and not np.array_equal(fields, regions):
        rows = np.flatnonzero(fields != regions)
        said = ["two" if r == -1 else int(r) for r in fields[rows]]
        raise DeckError(f"indentsim's fields put the rows of elements {rows.tolist()} (from the base) in regions "
                        f"{said}, the layers' depths in {regions[rows].tolist()}")
    return regions


def hardening_table(material, largest_strain_intensity, points=100, key="material"):
    """ccx's *PLASTIC table (von Mises stress, equivalent plastic strain) of indentsim's J2 law, up to
    twice the largest strain intensity of the run (beyond its last point ccx's curve is flat; for a
    layer, the run's largest, over every region, reaches at least as far as its own)."""
    E, nu, e0 = material["E"], material["nu"], material["e0"]
    mu = E / (2.0 * (1.0 + nu))
    if material["hardening"] == "linear":
        kappa = material["kappa"]
        if kappa == 0.0:
            raise DeckError(f"{key}.kappa = 0 is elastic: no plastic flow to compare")
        # omega = kappa (1 - e0/e_u): sigma_u = 3 mu e0 + 3 mu (1 - kappa)(e_u - e0), eps_p = kappa (e_u - e0).
        slope = 3.0 * mu * (1.0 - kappa) / kappa
        top = 100.0
        return [(3.0 * mu * e0, 0.0), (3.0 * mu * e0 + slope * top, top)]
    n = material["n"]
    # omega = 1 - (e0/e_u)^(1-n): sigma_u = 3 mu e0 (e_u/e0)^n, eps_p = e_u - sigma_u / (3 mu), at
    # points evenly spaced in log e_u: linear interpolation between them is off by about
    # n (1 - n) (log step)^2 / 8 of the stress (4e-6 for n = 0.2 and 100 points up to 4 e0).
    table = [(3.0 * mu * e0, 0.0)]
    for ratio in np.geomspace(1.0 + 1e-9, max(2.0, 2.0 * largest_strain_intensity / e0), points):
        stress = 3.0 * mu * e0 * ratio ** n
        table.append((stress, e0 * ratio - stress / (3.0 * mu)))
    return table


def expected_difference(scene, points=100):
    """How far ccx's P may lie from indentsim's, relative to the peak P, on a correct scene, and how
    large a replay's residual may be, relative to the largest contact reaction: the sources of
    difference the deck itself brings, each bounded from its own error:
      * 1e-6: ccx's 7 printed digits and both codes' equilibrium tolerances (measured 1e-8 to 2e-7
        on the plane-strain scenes with an elastic or linear-hardening specimen);
      * axisymmetry: twice (1 degree)^2, the straight-sided 2-degree wedge's departure from the ring
        (measured 1.6e-4 to 3.0e-4 on the shipped cases, up to 3.9e-4 on 57 random ones; 4.4e-4 on
        steel_sphere.toml under a J2 film, 2e-5 m, 2 GPa, n = 0.2, whose displacements the exact
        ring's Q1 forces, with each region's J2 update, balance to 3e-9 of the largest contact
        reaction, as they do the homogeneous case's; the same scene in plane strain: 8e-6);
      * the power law's table: n (1 - n) (log step)^2 / 8, the largest relative error of linear
        interpolation between the table's points (on power_law.toml with J2 and on the Berkovich cone
        in plane strain it gives 1.8e-5 and 2.7e-5; measured: 2.6e-6 and 4.0e-6 in P, 7.6e-6 and
        2.1e-5 in the residual).  A node's residual gathers the errors of the four elements around
        it: four times this for the residual (on 28 random plane-strain power-law cases P differed
        by up to 0.8 times it and the residual was up to 2.2 times it, growing as the square of
        the log step: 3.5 times from 100 to 60 points).  On a coated specimen, the largest of its
        J2 power-law regions' bounds: each region's stress is off by at most its own, so P, and a
        node's residual even where its four elements lie in two regions, by at most the largest.
    Returns (for P, for the residual)."""
    base = 1e-6
    if scene["kind"] == "axisymmetric":
        base += 2.0 * math.radians(1.0) ** 2
    table = 0.0
    for _, material in region_materials(scene["case"]):
        if material["model"] == "j2" and material["hardening"] == "power":
            step = math.log(max(2.0, 2.0 * scene["largest_strain_intensity"] / material["e0"])) / (points - 1)
            table = max(table, material["n"] * (1.0 - material["n"]) * step * step / 8.0)
    return base + table, base + 4.0 * table


def length_unit(scene):
    """The deck's unit of length: the specimen's height.  ccx refuses elements whose Jacobian
    determinant is below an absolute threshold ("nonpositive jacobian"), which a Berkovich cone's
    0.3 mm specimen, expanded into a 2-degree wedge, reaches in metres."""
    return scene["case"]["geometry"]["ly"]


def force_scale(scene):
    """From ccx's printed force [N] to indentsim's P: both halves of the plane-strain model, whose
    thickness is one length unit [N/m], the whole ring from the 2-degree wedge [N]; compression
    positive."""
    return {"plane_strain": -2.0 / length_unit(scene), "axisymmetric": -180.0}[scene["kind"]]


# ---------------------------------------------------------------------------------------------
# The deck


def write_deck(path, scene, contact="replay"):
    """The deck; returns the number of free displacement unknowns of the 2-D model.  Lengths in
    units of length_unit(scene), forces in newtons (stresses in N per unit length squared)."""
    unit = length_unit(scene)
    case, xs, ys = scene["case"], scene["xs"] / unit, scene["ys"] / unit
    punch = case["punch"]
    stress_unit = 1.0 / (unit * unit)  # pascals per deck stress unit
    materials = region_materials(case)
    for key, material in materials:
        check_material(key, material)
    # Region k's element set and material: the substrate's keep a homogeneous deck's names.
    names = [("EBLOCK", "SPECIMEN")] + [(f"ELAYER{k}", f"LAYER{k}") for k in range(1, len(materials))]
    row_region = row_regions(scene)
    if case["mesh"].get("element") != "q1":
        raise DeckError("mesh.element must be \"q1\": ccx's CPE4/CAX4 have no mean-dilatation (B-bar) variant")
    if contact in ("given", "replay") and scene["contact_sets"] is None:
        raise DeckError("the contact set of every increment needs the run's fields at every increment "
                        "(output.fields_every = 1)")
    gap_m, rim_m = punch_gap(punch)
    gap, rim = (lambda x: gap_m(x * unit) / unit), rim_m / unit
    element = {"plane_strain": "CPE4", "axisymmetric": "CAX4"}[scene["kind"]]
    nx, ny = len(xs), len(ys)
    node = lambda i, j: j * nx + i + 1  # j = 0 the base, j = ny - 1 the loaded surface
    models = " on ".join(material["model"] for _, material in materials[1:] + materials[:1])  # surface down
    lines = ["*HEADING", f"indentsim scene, {scene['kind']}, {punch['shape']}, {models}, {nx} x {ny} nodes",
             "*NODE, NSET=NALL"]
    w = lines.append
    for j in range(ny):
        for i in range(nx):
            w(f"{node(i, j)}, {xs[i]:.12e}, {ys[j]:.12e}, 0.0")
    e = 0
    for j in range(ny - 1):
        if j == 0 or row_region[j] != row_region[j - 1]:
            # The regions are bands of rows, so each set's elements are one card's.
            w(f"*ELEMENT, TYPE={element}, ELSET={names[row_region[j]][0]}")
        for i in range(nx - 1):
            e += 1
            w(f"{e}, {node(i, j)}, {node(i + 1, j)}, {node(i + 1, j + 1)}, {node(i, j + 1)}")
    w("*NSET, NSET=BASE")
    lines.extend(f"{node(i, 0)}," for i in range(nx))
    w("*NSET, NSET=AXIS")
    lines.extend(f"{node(0, j)}," for j in range(1, ny))
    w("*NSET, NSET=TOP")
    lines.extend(f"{node(i, ny - 1)}," for i in range(nx))
    for (key, material), (elset, name) in zip(materials, names):
        w(f"*MATERIAL, NAME={name}")
        w("*ELASTIC")
        w(f"{material['E'] / stress_unit:.12e}, {material['nu']:.12g}")
        if material["model"] == "j2":
            w("*PLASTIC")
            table = hardening_table(material, scene["largest_strain_intensity"], key=key)
            lines.extend(f"{stress / stress_unit:.12e}, {strain:.12e}" for stress, strain in table)
        w(f"*SOLID SECTION, ELSET={elset}, MATERIAL={name}")
        if element == "CPE4":
            w("1.0")
    alphas = [alpha / unit for alpha in scene["alphas"]]
    if contact in ("given", "replay"):
        for k in range(1, len(alphas)):
            # One ccx step, of one increment, per indentsim increment.
            w("*STEP")
            w("*STATIC, DIRECT")
            w("1.0, 1.0")
            if contact == "given":
                # Residual and correction tests 1e-7 of the average force instead of 0.005 (ccx
                # manual, *CONTROLS): J2's equilibrium to the digits compared.
                w("*CONTROLS, PARAMETERS=FIELD")
                w("1e-7, 1e-7, 1e-5, 1e-2, 0.02, 1e-5, 1e-3, 1e-8")
                w("*CONTROLS, PARAMETERS=TIME INCREMENTATION")
                w("200, 200, 200, 200, 10, 200, 0, 200")
                w("*BOUNDARY, OP=NEW")
                w("BASE, 1, 2, 0.0")
                w("AXIS, 1, 1, 0.0")
                for i in scene["contact_sets"][k]:
                    w(f"{node(i, ny - 1)}, 2, 2, {-alphas[k] + gap(xs[i]):.12e}")
                w("*NODE PRINT, NSET=TOP")
                w("U, RF")
            else:
                # Every node where indentsim put it: ccx updates the stresses along the same
                # strain path and reports, as the reaction at each node, its own element forces.
                w("*BOUNDARY, OP=NEW")
                for n, (u1, u2) in enumerate(scene["displacements"][k] / unit):
                    w(f"{n + 1}, 1, 1, {u1:.12e}")
                    w(f"{n + 1}, 2, 2, {u2:.12e}")
                w("*NODE PRINT, NSET=NALL")
                w("RF")
            w("*END STEP")
    elif contact == "gap":
        write_gap_contact(lines, xs, ys, alphas, scene, gap, rim, node)
    else:
        raise DeckError(f"contact = \"{contact}\": \"given\", \"replay\" or \"gap\"")
    path.write_text("\n".join(lines) + "\n")
    return 2 * (nx * ny - nx) - (ny - 1)  # free DOFs: base fixed, axis held in x


def write_gap_contact(lines, xs, ys, alphas, scene, gap, rim, node):
    """Gap elements to a rigid punch node driven through the run's depths (contact = "gap"); all
    lengths in the deck's unit."""
    w = lines.append
    nx, ny = len(xs), len(ys)
    punch_node = nx * ny + 1
    h = float(np.min(np.diff(xs)))
    reach = min(2.0 * max(scene["half_widths"]) / length_unit(scene) + 2.0 * h, rim)
    candidates = [i for i in range(nx) if xs[i] <= reach]
    if candidates[-1] == nx - 1:
        raise DeckError("the contact reaches the specimen's side: no scene of MODEL.md")
    w("*NODE, NSET=PUNCH")
    w(f"{punch_node}, 0.0, {ys[-1] - ys[0]:.12e}, 0.0")
    e = (nx - 1) * (ny - 1)
    for i in candidates:
        e += 1
        w(f"*ELEMENT, TYPE=GAPUNI, ELSET=G{i}")
        w(f"{e}, {node(i, ny - 1)}, {punch_node}")
    materials = [material for _, material in region_materials(scene["case"])]
    if all(material["model"] == "elastic" for material in materials):
        # Unused, but it makes ccx iterate (see the pitfalls above); a region's own *PLASTIC does too.
        w("*MATERIAL, NAME=NONLINEAR_TRIGGER")
        w("*ELASTIC")
        w("1.0, 0.0")
        w("*PLASTIC")
        w("1.0e30, 0.0")
    # The penalty against the stiffest region's E: no region's compliance then hides the gap's (the
    # factor 1e9 leaves P unchanged to the printed digits, see the pitfalls above).
    stiffness = 1e9 * max(material["E"] for material in materials) * length_unit(scene) ** 2 * h
    if scene["kind"] == "axisymmetric":
        stiffness *= xs[-1] * math.radians(2.0)  # the wedge's circumference at the outer radius
    # The tension of an open gap: the force of a penetration 1e-21 of the deepest depth.
    tension = stiffness * max(alphas) * 1e-21
    for i in candidates:  # clearance, direction, (unused), stiffness, tension of an open gap
        w(f"*GAP, ELSET=G{i}")
        w(f"{gap(xs[i]):.12e}, 0., 1., 0., , {stiffness:.6e}, {tension:.6e}")
    w("*BOUNDARY")
    w("BASE, 1, 2, 0.0")
    w("AXIS, 1, 1, 0.0")
    w(f"{punch_node}, 1, 1, 0.0")
    w(f"{punch_node}, 3, 3, 0.0")
    w("*AMPLITUDE, NAME=DEPTH")
    pairs = [f"{k:.1f}, {alpha:.12e}" for k, alpha in enumerate(alphas)]
    lines.extend(", ".join(pairs[i:i + 4]) for i in range(0, len(pairs), 4))
    w("*STEP, INC=100000")
    w("*STATIC, DIRECT")
    w(f"1.0, {len(alphas) - 1:.1f}")
    w("*BOUNDARY, AMPLITUDE=DEPTH")
    w(f"{punch_node}, 2, 2, -1.0")
    w("*NODE PRINT, NSET=PUNCH, TOTALS=ONLY")
    w("RF")
    w("*END STEP")


# ---------------------------------------------------------------------------------------------
# Running ccx and reading its answer


def run_ccx(ccx, workdir, job, unit):
    """Runs ccx on one thread; returns the surface's displacements and reaction forces at every
    increment ({"U": [array (nx, 2)], "RF": [...]}, index 0 the first increment; with gap elements
    also the punch node's vertical reaction, "punch") and the wall time."""
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1", CCX_NPROC_EQUATION_SOLVER="1",
               CCX_NPROC_RESULTS="1")
    start = time.perf_counter()
    proc = subprocess.run([ccx, "-i", job], cwd=workdir, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    (workdir / f"{job}.log").write_text(proc.stdout + proc.stderr)
    if proc.returncode != 0 or "*ERROR" in proc.stdout:
        tail = "\n".join(line for line in proc.stdout.splitlines()[-30:] if line.strip())
        raise DeckError(f"ccx failed (rc {proc.returncode}); deck and log in {workdir}\n{tail}")
    text = (workdir / f"{job}.dat").read_text()
    result = {}
    for key, title, node_set in (("U", "displacements", "TOP"), ("RF", "forces", "TOP"), ("RF_all", "forces", "NALL")):
        blocks = re.findall(rf" {title} \(\w+,\w+,\w+\) for set {node_set} and time\s+(\S+)\s*\n\s*\n"
                            r"((?:\s+\d+(?:\s+\S+){3}\n)+)", text)
        scale = unit if key == "U" else 1.0  # displacements back to metres
        result[key] = [scale * np.array([[float(v) for v in line.split()[1:3]] for line in block.strip().splitlines()])
                       for t, block in blocks if abs(float(t) - round(float(t))) < 1e-9]
    totals = re.findall(r"total force \(fx,fy,fz\) for set PUNCH and time\s+(\S+)\s*\n\s*\n?\s*(\S+)\s+(\S+)", text)
    result["punch"] = [float(fy) for t, _, fy in totals if abs(float(t) - round(float(t))) < 1e-9]
    return result, wall


def forces_of(scene, result, contact):
    """P at every increment from 1 on: the punch node's reaction with gap elements, the sum of the
    surface's vertical reactions with the given contact set."""
    scale = force_scale(scene)
    if contact == "gap":
        return [scale * f for f in result["punch"]]
    if contact == "replay":
        top = (len(scene["ys"]) - 1) * len(scene["xs"])
        return [scale * float(np.sum(rf[top:, 1])) for rf in result["RF_all"]]
    return [scale * float(np.sum(rf[:, 1])) for rf in result["RF"]]


def replay_residual(scene, k, rf_all):
    """ccx's element forces at the unknowns indentsim solved for in its replayed increment k, and
    the largest contact reaction there: the first is 0 where indentsim's displacements are in
    equilibrium by ccx's elements and J2 update.  The unknowns: every displacement but the base's,
    the axis nodes' x and the contact nodes' y (those carry reactions); a contact node's x is an
    unknown (frictionless: no tangential reaction).  In axisymmetry only the vertical forces count:
    the radial force ccx prints at a node of its expanded wedge is not its radial residual (at the
    free surface nodes of ccx's own converged solution it is 1% of the largest contact reaction,
    where the vertical one is 1e-15)."""
    nx, ny = len(scene["xs"]), len(scene["ys"])
    free = np.ones((nx * ny, 2), dtype=bool)
    free[:nx, :] = False                 # the base
    free[::nx, 0] = False                # the axis, x
    if scene["kind"] == "axisymmetric":
        free[:, 0] = False
    contact = [(ny - 1) * nx + i for i in scene["contact_sets"][k]]
    free[contact, 1] = False
    largest_reaction = float(np.max(np.abs(rf_all[contact, 1]))) if contact else 0.0
    return float(np.max(np.abs(rf_all[free]))), largest_reaction


def check_signorini(scene, k, u, rf):
    """The Signorini conditions (MODEL.md) at increment k, from ccx's reactions rf at the surface
    and the surface's displacements u: the largest pull of a contact node and the largest push
    (ccx's force units), and the deepest penetration of a free node through the punch [m]; the
    first and the last are 0 where the conditions hold."""
    gap, rim = punch_gap(scene["case"]["punch"])
    alpha, contact = scene["alphas"][k], set(scene["contact_sets"][k])
    pushes = [-rf[i, 1] for i in contact]
    penetration = max([0.0] + [u[i, 1] - (-alpha + gap(x)) for i, x in enumerate(scene["xs"])
                               if i not in contact and x < rim])
    return max([0.0] + [-p for p in pushes]), max([0.0] + pushes), penetration
