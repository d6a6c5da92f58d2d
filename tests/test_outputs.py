#!/usr/bin/env python3
"""Output files of a run, read as a user's tools would read them.

    test_outputs.py INDENTSIM_EXECUTABLE SOURCE_DIR

Runs a small plastic case with fields at every increment, then checks that
  - every VTU is well-formed XML of the VTK UnstructuredGrid format with array sizes matching
    the mesh (points = nx * ny from the coordinates themselves, cells = (nx-1)(ny-1), quads),
  - fields.pvd lists exactly those files with the increment as time (strictly increasing, also
    along loadcases/load_unload.toml where alpha returns to 0), each VTU carrying its alpha and
    step as field data,
  - layers.csv and profiles.csv have the promised columns and rows,
  - plots/plot_results.py writes non-empty PNG and SVG figures.
Prints 'N passed, N failed' and exits non-zero on any failure.
"""
import base64
import csv
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy

failures = []
passed = 0


def check(condition, message):
    global passed
    if condition:
        passed += 1
    else:
        failures.append(message)
        print("FAIL:", message)


def data_arrays(parent):
    return {d.get("Name"): d for d in parent.findall("DataArray")}


NUMPY_TYPES = {"Float64": "<f8", "Int32": "<i4", "Int64": "<i8", "UInt8": "u1"}


def values_of(array):
    """The values of a DataArray as VTK's XML reader decodes them: format="binary" is base64 of a
    UInt64 byte count (the file's header_type) followed by the raw little-endian values."""
    if array.get("format") != "binary":
        return array.text.split()
    raw = base64.b64decode("".join(array.text.split()), validate=True)
    size = int.from_bytes(raw[:8], "little")
    check(size == len(raw) - 8, f"DataArray {array.get('Name')}: header says {size} bytes, {len(raw) - 8} follow")
    return numpy.frombuffer(raw[8:8 + size], dtype=NUMPY_TYPES[array.get("type")]).tolist()


def check_vtu(path):
    root = ET.parse(path).getroot()
    check(root.tag == "VTKFile" and root.get("type") == "UnstructuredGrid", f"{path.name}: not a VTK UnstructuredGrid")
    check(root.get("byte_order") == "LittleEndian" and root.get("header_type") == "UInt64", f"{path.name}: binary layout")
    piece = root.find("UnstructuredGrid").find("Piece")
    points, cells = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells"))
    coordinates = [float(v) for v in values_of(data_arrays(piece.find("Points"))["coordinates"])]
    check(len(coordinates) == 3 * points, f"{path.name}: coordinates size")
    nx = len({coordinates[3 * k] for k in range(points)})
    ny = len({coordinates[3 * k + 1] for k in range(points)})
    check(points == nx * ny, f"{path.name}: {points} points for a {nx} x {ny} grid")
    check(cells == (nx - 1) * (ny - 1), f"{path.name}: {cells} cells for a {nx} x {ny} grid")
    for section, count in (("PointData", points), ("CellData", cells)):
        arrays = data_arrays(piece.find(section))
        check(len(arrays) >= 5, f"{path.name}: {section} has {len(arrays)} arrays")
        for name, array in arrays.items():
            values = values_of(array)
            components = int(array.get("NumberOfComponents", "1"))
            check(len(values) == count * components, f"{path.name}: {section}/{name} has {len(values)} values")
    for name in ("displacement", "sigma22", "contact_status"):
        check(name in data_arrays(piece.find("PointData")), f"{path.name}: point array {name} missing")
    for name in ("strain_intensity", "omega", "plastic"):
        check(name in data_arrays(piece.find("CellData")), f"{path.name}: cell array {name} missing")
    cell_arrays = data_arrays(piece.find("Cells"))
    connectivity = [int(v) for v in values_of(cell_arrays["connectivity"])]
    offsets = [int(v) for v in values_of(cell_arrays["offsets"])]
    types = [int(v) for v in values_of(cell_arrays["types"])]
    check(len(connectivity) == 4 * cells and all(0 <= n < points for n in connectivity), f"{path.name}: connectivity")
    check(offsets == [4 * (e + 1) for e in range(cells)], f"{path.name}: offsets")
    check(types == [9] * cells, f"{path.name}: cell types are not all VTK_QUAD")


def field_data(path):
    """(alpha, step) from a VTU's FieldData."""
    arrays = data_arrays(ET.parse(path).getroot().find("UnstructuredGrid").find("FieldData"))
    return float(arrays["alpha"].text), int(arrays["step"].text)


def main():
    executable, source = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "run"
        run = subprocess.run([str(executable), "run", str(source / "loadcases" / "deep_plastic.toml"), "--quiet",
                              "--out", str(out), "--set", "mesh.contact_nodes=6", "--set", "load.increments=3",
                              "--set", "output.fields_every=1", "--set", "output.profile_depths=[2e-4, 5e-4]"],
                             capture_output=True, text=True)
        check(run.returncode == 0, f"indentsim run failed: {run.stderr}")
        if run.returncode != 0:
            return

        with open(out / "curve.csv", newline="") as f:
            curve = list(csv.DictReader(f))
        collection = ET.parse(out / "fields.pvd").getroot()
        check(collection.get("type") == "Collection", "fields.pvd is not a VTK collection")
        datasets = collection.find("Collection").findall("DataSet")
        check(len(datasets) == len(curve), f"fields.pvd lists {len(datasets)} data sets for {len(curve)} increments")
        for dataset, row in zip(datasets, curve):
            check(int(dataset.get("timestep")) == int(row["step"]), "pvd time is not the increment")
            vtu = out / dataset.get("file")
            check(vtu.is_file(), f"{vtu} listed but missing")
            if vtu.is_file():
                check_vtu(vtu)
                check(field_data(vtu) == (float(row["alpha"]), int(row["step"])), f"{vtu.name}: alpha/step field data")

        # A load-unload-reload history: alpha = 0 three times, the series still plays in order.
        history = pathlib.Path(tmp) / "history"
        run = subprocess.run([str(executable), "run", str(source / "loadcases" / "load_unload.toml"), "--quiet",
                              "--out", str(history), "--set", "mesh.contact_nodes=6", "--set", "output.fields_every=1"],
                             capture_output=True, text=True)
        check(run.returncode == 0, f"indentsim run of load_unload.toml failed: {run.stderr}")
        with open(history / "curve.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        times = [int(d.get("timestep")) for d in ET.parse(history / "fields.pvd").getroot().find("Collection")]
        check(times == [int(r["step"]) for r in rows], "load_unload: one pvd entry per increment, in order")
        check(all(b > a for a, b in zip(times, times[1:])), "load_unload: pvd times not strictly increasing")
        check(sum(1 for r in rows if float(r["alpha"]) == 0.0) >= 2, "load_unload: the path returns to alpha = 0")

        # A history that ends unloaded: the deepest state's fields and layer view are written, and
        # the figures show it by default.
        unloaded = pathlib.Path(tmp) / "unloaded"
        run = subprocess.run([str(executable), "run", str(source / "loadcases" / "load_unload.toml"), "--quiet",
                              "--out", str(unloaded), "--set", "mesh.contact_nodes=6", "--set", "load.path=[0, 5e-5, 0]",
                              "--set", "load.increments=[4, 4]"], capture_output=True, text=True)
        check(run.returncode == 0, f"indentsim run (unloaded end) failed: {run.stderr}")
        with open(unloaded / "profiles.csv", newline="") as f:
            steps = sorted({int(r["step"]) for r in csv.DictReader(f)})
        check(steps == [4, 8], f"profiles.csv holds steps {steps}, expected the peak (4) and the end (8)")
        check((unloaded / "fields" / "step_000004.vtu").is_file(), "the peak's fields were not written")
        plot = subprocess.run([str(executable), "plot", str(unloaded)], capture_output=True, text=True)
        check(plot.returncode == 0, f"indentsim plot (unloaded end) failed: {plot.stderr}")
        check("= 50 µm (step 4)" in (unloaded / "figures" / "pressure.svg").read_text(),
              "the pressure figure is not the peak's (h = 50 µm, step 4)")

        # indentsim analyze --plot: analysis.json and its figure (the fit, S, h_c and the table).
        sphere = pathlib.Path(tmp) / "sphere"
        run = subprocess.run([str(executable), "run", str(source / "loadcases" / "axisymmetric" / "elastic_sphere.toml"),
                              "--quiet", "--out", str(sphere), "--set", "mesh.contact_nodes=8",
                              "--set", "load.path=[0, 5e-6, 0]", "--set", "load.increments=[6, 10]"],
                             capture_output=True, text=True)
        check(run.returncode == 0, f"indentsim run (elastic sphere) failed: {run.stderr}")
        analyze = subprocess.run([str(executable), "analyze", str(sphere), "--plot"], capture_output=True, text=True)
        check(analyze.returncode == 0, f"indentsim analyze --plot failed: {analyze.stderr}")
        report = json.loads((sphere / "analysis.json").read_text())
        check(report["units"]["stress"] == "Pa" and len(report["branches"]) == 1, "analysis.json: units and one branch")
        for suffix in ("png", "svg"):
            figure = sphere / f"analysis.{suffix}"
            check(figure.is_file() and figure.stat().st_size > 1000, f"analysis.{suffix} missing or empty")
        check("Oliver-Pharr" in (sphere / "analysis.svg").read_text(), "the analysis figure has no table")

        with open(out / "layers.csv", newline="") as f:
            layers = list(csv.DictReader(f))
        check(len(layers) > 10 and {"y", "P_minus", "P_plus", "mismatch"} <= set(layers[0]), "layers.csv columns")
        with open(out / "profiles.csv", newline="") as f:
            profiles = list(csv.DictReader(f))
        check(len({r["line"] for r in profiles}) == 3, "profiles.csv: surface plus two depths")
        check({"sigmaN_layer", "sigmaT_layer", "sigma22_nodal", "sigma12_nodal"} <= set(profiles[0]),
              "profiles.csv columns")
        check((out / "case.toml").is_file(), "case.toml missing")

        # The README's command, exactly: `indentsim plot DIR`, with a python3 first on the PATH that
        # has no matplotlib (as on machines where python3 is not Debian's).
        fake_bin = pathlib.Path(tmp) / "fake_bin"
        fake_bin.mkdir()
        (fake_bin / "python3").write_text("#!/bin/sh\necho \"ModuleNotFoundError: No module named 'matplotlib'\" >&2\n"
                                          "exit 1\n")
        (fake_bin / "python3").chmod(0o755)
        environment = dict(os.environ, PATH=f"{fake_bin}:{os.environ.get('PATH', '')}")
        plot = subprocess.run([str(executable), "plot", str(out)], capture_output=True, text=True, env=environment)
        check(plot.returncode == 0, f"indentsim plot failed: {plot.stderr}")
        for name in ("curve", "pressure", "profiles", "plastic_zone"):
            for suffix in ("png", "svg"):
                figure = out / "figures" / f"{name}.{suffix}"
                check(figure.is_file() and figure.stat().st_size > 1000, f"{figure.name} missing or empty")


main()
print(f"{passed} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
