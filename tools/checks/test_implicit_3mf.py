"""Lattices and infills written as 3MF implicit functions (`pgvol lattice … -o X.3mf`,
`pgvol shell … --infill … -o X.3mf`).

lib3mf 2.5 reads each package as it reads its own (lib3mf_oracle), and hands back the same node
graph as the XML, every node's types valid. The graph is then evaluated by implicit_eval (numpy,
from the XML and the PNG sheets, nothing of pgvol's) at grid nodes of the part and compared with
`pgvol eval` of the same lattice written as a dense `.pgv`.

Tolerance at the nodes, `h / 64` (h the grid spacing): the image stack stores the part's values
in steps of `h / 64` (error at most `h / 128`, passed on with slope at most 1 by the max, min and
the depth ramp); pgvol's `.pgv` holds the lattice's node values through an interpolating fit in
f32 (a few 1e-6 of the cell here); the rest is f32 against f64 arithmetic. Where pgvol's value is
above one spacing the image clamps the part (outside the solid only the sign is kept, see
docs/interop.md), so there the graph must only be positive.
"""

from __future__ import annotations

import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import helpers
import lib3mf_oracle
from implicit_eval import NS, Package

RES = 64
SHEETS_CHECKED = 6
NODES_PER_SHEET = 500

# (name, command, arguments): spot is about 1.9 units across, h = 0.03 at 64³.
CASES = [
    ("gyroid-linear", "lattice", ["--surface", "gyroid", "--cell", "0.4", "--thickness", "0.08",
                                  "--grade-linear", "-1,0,0,1,0,0", "--cell-far", "0.6",
                                  "--thickness-far", "0.12"]),
    ("schwarz-p-strut", "lattice", ["--surface", "schwarz-p", "--style", "strut", "--cell", "0.5",
                                    "--thickness", "-0.04"]),
    ("neovius-sheet", "lattice", ["--surface", "neovius", "--cell", "0.5", "--thickness", "0.08"]),
    ("diamond-infill", "shell", ["--thickness", "0.1", "--infill", "diamond", "--cell", "0.4",
                                 "--infill-thickness", "0.08", "--grade-depth", "0.3",
                                 "--thickness-far", "0.12", "--drain", "0,0,0,0,0,-1,0.2"]),
]


def xml_graph(package):
    """(identifier, element, {input: reference}) of each node of the level set's function."""
    nodes = []
    for node in package.implicit_function():
        kind = node.tag.split("}")[1]
        if kind in ("in", "out"):
            continue
        block = node.find("i:in", NS)
        refs = {r.get("identifier"): r.get("ref") for r in (block if block is not None else [])}
        nodes.append((node.get("identifier"), kind, refs))
    return nodes


def lib3mf_graph(function):
    import lib3mf

    # lib3mf's enum names are the element names but for the trigonometric ones.
    renamed = {"sinus": "sin", "cosinus": "cos"}
    names = {
        v: renamed.get(k.lower(), k.lower())
        for k, v in vars(lib3mf.ImplicitNodeType).items()
        if isinstance(v, int)
    }
    nodes, it = [], function.GetNodes()
    while it.MoveNext():
        node = it.GetCurrent()
        assert node.AreTypesValid(), node.GetIdentifier()
        refs, ports = {}, node.GetInputs()
        while ports.MoveNext():
            port = ports.GetCurrent()
            refs[port.GetIdentifier()] = port.GetReference()
        nodes.append((node.GetIdentifier(), names[node.GetNodeType()], refs))
    return nodes


@pytest.fixture(scope="module")
def folder(work_dir):
    out = work_dir / "implicit-3mf"
    out.mkdir(parents=True, exist_ok=True)
    return out


@pytest.mark.parametrize("name,command,args", CASES, ids=[c[0] for c in CASES])
def test_implicit_lattice_reads_in_lib3mf_and_evaluates_as_pgvol(pgvol, mesh_path, folder, name, command, args):
    mesh = mesh_path("spot")
    out, pgv = folder / f"{name}.3mf", folder / f"{name}.pgv"
    common = ["--res", RES]
    helpers.run_ok([pgvol, command, mesh, "-o", out, *args, *common, "--unit", "centimeter"])
    helpers.run_ok([pgvol, command, mesh, "-o", pgv, *args, *common, "--dense-file"])
    info = helpers.run_json([pgvol, "info", pgv, "--json"])
    g = info["header"]["grid"]
    origin, h, dims = np.asarray(g["origin"], float), float(g["spacing"]), tuple(g["dims"])

    package = Package(out)
    with zipfile.ZipFile(out) as z:
        root = ET.fromstring(z.read("3D/3dmodel.model"))
    assert set(root.get("requiredextensions").split()) == {"v", "i"}
    assert root.get("unit") == "centimeter"
    stack = root.find(".//v:imagestack", NS)
    assert (int(stack.get("columncount")), int(stack.get("rowcount")), int(stack.get("sheetcount"))) == dims

    # lib3mf: as its own package of the same stack reads, and the same graph as the XML.
    reference = lib3mf_oracle.reference_package(out, folder / f"{name}-by-lib3mf.3mf", dims)
    model = lib3mf_oracle.check_reads_as_lib3mf_own(out, reference).model
    levelsets = lib3mf_oracle.levelsets(model)
    assert len(levelsets) == 1
    levelset = levelsets[0]
    written = package.levelset()
    assert levelset.GetChannelName() == written.get("channel") == "shape"
    assert levelset.GetFallBackValue() == pytest.approx(float(written.get("fallbackvalue")), rel=1e-6)
    assert levelset.GetMinFeatureSize() == pytest.approx(h, rel=1e-6)
    box = model.GetMeshObjectByID(levelset.GetMesh().GetResourceID())
    assert (box.GetVertexCount(), box.GetTriangleCount()) == (8, 12)
    function = lib3mf_oracle.functions(model)[levelset.GetFunction().GetResourceID()]
    assert sorted(lib3mf_graph(function)) == sorted(xml_graph(package))

    # The graph at grid nodes of a few sheets against pgvol eval of the same lattice.
    rng = np.random.default_rng(7)
    ks = rng.choice(np.arange(2, dims[2] - 2), size=SHEETS_CHECKED, replace=False)
    idx = np.concatenate([
        np.column_stack([rng.integers(0, dims[0], NODES_PER_SHEET), rng.integers(0, dims[1], NODES_PER_SHEET),
                         np.full(NODES_PER_SHEET, k)])
        for k in ks
    ])
    points = origin + h * idx
    got = package.levelset_values(points)
    csv, values_csv = folder / f"{name}-points.csv", folder / f"{name}-values.csv"
    np.savetxt(csv, points, delimiter=",", fmt="%.9g")
    helpers.run_ok([pgvol, "eval", pgv, csv, "-o", values_csv])
    want = np.loadtxt(values_csv, delimiter=",", skiprows=1, ndmin=2)[:, 3]

    near = want <= h
    tol = h / 64
    err = np.abs(got - want)[near]
    assert near.sum() >= 200 and (want < 0).sum() >= 100, (near.sum(), (want < 0).sum())
    print(f"{name}: {near.sum()} nodes compared, max error {err.max() / h:.2e} h (tol {tol / h:.3g} h)")
    assert err.max() <= tol, f"{name}: graph off pgvol eval by {err.max():.3g} at nodes (tol {tol:.3g})"
    assert (got[~near] > 0).all(), f"{name}: graph not outside where pgvol is {want[~near][got[~near] <= 0]}"
    # The lattice is there: inside the part the values change sign.
    assert got.min() < 0 < got.max()
    assert {"sin", "cos", "functioncall", "clamp", "length"} <= package.evaluated_nodes


def test_graded_gyroid_infill_of_the_bunny_is_a_twentieth_of_its_stl(pgvol, mesh_path, folder):
    """The same graded gyroid infill of the bunny at 256³: the implicit 3MF against the binary STL
    of its contoured surface."""
    mesh = mesh_path("stanford-bunny")
    args = ["--thickness", "0.006", "--infill", "gyroid", "--cell", "0.02", "--infill-thickness", "0.0025",
            "--grade-depth", "0.03", "--thickness-far", "0.0015", "--res", "256"]
    stl, tmf = folder / "bunny-infill.stl", folder / "bunny-infill.3mf"
    helpers.run_ok([pgvol, "shell", mesh, "-o", stl, *args])
    helpers.run_ok([pgvol, "shell", mesh, "-o", tmf, *args])
    stl_bytes, tmf_bytes = stl.stat().st_size, tmf.stat().st_size
    with open(stl, "rb") as f:
        f.seek(80)
        triangles = int(np.frombuffer(f.read(4), "<u4")[0])
    assert stl_bytes == 84 + 50 * triangles > 0, "not a binary STL"
    assert triangles > 1_000_000, triangles
    ratio = stl_bytes / tmf_bytes
    print(f"bunny infill at 256³: STL {stl_bytes} bytes ({triangles} triangles), 3MF {tmf_bytes} bytes, {ratio:.1f}x")
    assert ratio >= 20, f"3MF {tmf_bytes} bytes, STL {stl_bytes} bytes: only {ratio:.1f}x smaller"
    package = Package(tmf)
    assert package.levelset().get("channel") == "shape"
    assert {n[1] for n in xml_graph(package)} >= {"sin", "cos", "functioncall", "clamp"}


def test_implicit_outputs_refuse_what_they_cannot_write(pgvol, mesh_path, folder):
    mesh = mesh_path("spot")
    out = folder / "refused.3mf"
    plain = helpers.run([pgvol, "shell", mesh, "-o", out, "--thickness", 0.1, "--res", 32])
    assert plain.returncode != 0 and "--infill" in plain.stderr, plain.describe()
    # A part whose band does not reach the depth ramp: named, with the cause.
    pgv = folder / "narrow.pgv"
    helpers.run_ok([pgvol, "encode", mesh, "-o", pgv, "--res", 32])
    deep = helpers.run([pgvol, "lattice", pgv, "-o", out, "--surface", "gyroid", "--cell", 0.4,
                        "--thickness", 0.08, "--grade-depth", 1.5, "--thickness-far", 0.12])
    assert deep.returncode == 1 and "narrow.pgv" in deep.stderr and "band" in deep.stderr, deep.describe()
    bad = helpers.run([pgvol, "lattice", mesh, "-o", out, "--surface", "gyroid", "--cell", 0.4,
                       "--thickness", 0.3, "--res", 32])
    assert bad.returncode != 0 and "half the cell" in bad.stderr, bad.describe()
    unit = helpers.run([pgvol, "lattice", mesh, "-o", out, "--surface", "gyroid", "--cell", 0.4,
                        "--thickness", 0.08, "--res", 32, "--unit", "furlong"])
    assert unit.returncode != 0 and "refused.3mf" in unit.stderr and "millimeter" in unit.stderr, unit.describe()
    assert not out.exists()
