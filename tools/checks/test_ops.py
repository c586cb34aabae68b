"""`pgvol slice`, `pgvol offset` and `pgvol shell` on the shared meshes, checked against
manifold3d's exact cross-sections and its manifold test."""

from __future__ import annotations

import json

import manifold3d
import numpy as np
import pytest
import trimesh

import helpers

SLICE_RES = 256
AREA_TOLERANCE = 0.01
PERIMETER_TOLERANCE = 0.025


def loop_area(points) -> float:
    p = np.asarray(points, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def loop_perimeter(points) -> float:
    p = np.asarray(points, dtype=np.float64)
    return float(np.linalg.norm(p - np.roll(p, -1, axis=0), axis=1).sum())


def significant_loops(areas, layer_area: float) -> int:
    return sum(a >= 1e-3 * layer_area for a in areas)


@pytest.fixture(scope="session")
def closed_source(mesh_path, reference_mesh, work_dir):
    """closed_source(name) -> (trimesh mesh, path to slice). 'bunny-capped' is the open bunny
    with its five holes closed by fans, written next to the other outputs."""

    def _source(name: str):
        if name != "bunny-capped":
            return reference_mesh(name), mesh_path(name)
        capped = helpers.cap_holes(reference_mesh("stanford-bunny"))
        assert capped.is_watertight and capped.is_winding_consistent
        path = work_dir / "ops" / "bunny-capped.ply"
        path.parent.mkdir(parents=True, exist_ok=True)
        capped.export(path)
        return capped, path

    return _source


@pytest.mark.parametrize("name", ["bunny-capped", "fandisk", "spot"])
def test_slices_match_manifold_cross_sections(name, pgvol, closed_source, work_dir):
    ref, source = closed_source(name)
    lo, hi = ref.bounds
    height = float(hi[2] - lo[2])
    layer = height / 60
    out = work_dir / "ops" / f"{name}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok([pgvol, "slice", source, "-o", out, "--layer-height", layer, "--res", SLICE_RES, "-q"])
    layers = json.loads(out.read_text())["layers"]

    # Layer count and heights exactly as asked: first at half a layer, then every layer height.
    expected = int(np.floor((height - layer / 2) / layer + 1e-6)) + 1
    assert len(layers) == expected, (len(layers), expected)
    for i, l in enumerate(layers):
        assert abs(l["height"] - (lo[2] + layer / 2 + i * layer)) < 1e-4 * height

    solid = manifold3d.Manifold(helpers.manifold_mesh(ref))
    compared = same_count = 0
    perimeters = []
    for l in layers:
        section = solid.slice(l["height"])
        want = section.area()
        # Skip layers near horizontal faces or tips, where a tiny change in height changes a lot.
        if want < 0.02 * (hi[0] - lo[0]) * (hi[1] - lo[1]):
            continue
        got = sum(loop_area(loop["points"]) for loop in l["loops"])
        assert abs(got - want) <= AREA_TOLERANCE * want, f"{name} z={l['height']:.5f}: area {got} vs {want}"
        perimeters.append((
            sum(loop_perimeter(loop["points"]) for loop in l["loops"]),
            sum(loop_perimeter(poly) for poly in section.to_polygons()),
        ))
        for loop in l["loops"]:
            assert (loop_area(loop["points"]) < 0) == loop["hole"], "outer loops CCW, holes CW"
        compared += 1
        # Loops under a thousandth of the layer's area are below what the 1 % area check sees and
        # near a grid cell in size; count only the loops above that on both sides.
        ours = [abs(loop_area(loop["points"])) for loop in l["loops"]]
        theirs = [abs(loop_area(poly)) for poly in section.to_polygons()]
        same_count += significant_loops(ours, want) == significant_loops(theirs, want)
    assert compared >= 0.8 * len(layers) - 4
    # Loops are polygons through points of the true contour, simplified within a tenth of a
    # cell, so they run a little short of it; on the shared meshes by 0.2-1.6 % per layer.
    ratio = np.divide(*np.asarray(perimeters).T)
    assert np.all(np.abs(ratio - 1) <= PERIMETER_TOLERANCE), (name, ratio.min(), ratio.max())
    assert abs(np.median(ratio) - 1) <= AREA_TOLERANCE, (name, np.median(ratio))
    assert same_count >= 0.95 * compared, f"{name}: loop counts agree on {same_count} of {compared} layers"


SHARED_MESHES = ["stanford-bunny", "spot", "cow", "fandisk", "rocker-arm", "teapot", "suzanne"]
OPEN_MESHES = {"stanford-bunny", "teapot", "suzanne"}


@pytest.mark.parametrize("fraction", [0.05, -0.05])
@pytest.mark.parametrize("name", SHARED_MESHES)
def test_offsets_are_closed_manifolds(name, fraction, pgvol, mesh_path, reference_mesh, work_dir):
    ref = reference_mesh(name)
    distance = fraction * helpers.bbox_diagonal(ref)
    out = work_dir / "ops" / f"{name}-offset-{fraction}.glb"
    out.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok([pgvol, "offset", mesh_path(name), "-o", out, "--distance", distance, "--res", 96, "-q"])
    mesh = helpers.load_output(out)
    assert len(mesh.faces) > 0
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert helpers.manifold_ok(helpers.manifold_status(mesh)), helpers.manifold_status(mesh)
    # Open inputs have no volume of their own; the winding number closes them.
    if name in OPEN_MESHES:
        return
    if fraction > 0:
        assert mesh.volume > ref.volume
    else:
        assert 0 < mesh.volume < ref.volume


def test_hollowed_part_has_an_inner_cavity(pgvol, mesh_path, reference_mesh, work_dir):
    ref = reference_mesh("spot")
    wall = 0.02 * helpers.bbox_diagonal(ref)
    out = work_dir / "ops" / "spot-hollow.glb"
    helpers.run_ok([pgvol, "shell", mesh_path("spot"), "-o", out, "--thickness", wall, "--hollow", "--res", 96, "-q"])
    mesh = helpers.load_output(out)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert helpers.manifold_ok(helpers.manifold_status(mesh)), helpers.manifold_status(mesh)
    # Two nested surfaces: the outer skin and the inward-facing cavity.
    assert mesh.body_count == 2 or len(mesh.split(only_watertight=False)) == 2
    assert 0 < mesh.volume < 0.5 * ref.volume


def test_sparse_file_decodes_like_the_dense_one(pgvol, mesh_path, work_dir):
    folder = work_dir / "ops"
    sparse, dense = folder / "bunny.pgv", folder / "bunny-dense.pgv"
    helpers.run_ok([pgvol, "encode", mesh_path("stanford-bunny"), "-o", sparse, "--res", 64, "-q"])
    helpers.run_ok([pgvol, "encode", mesh_path("stanford-bunny"), "-o", dense, "--res", 64, "--dense-file", "-q"])
    info = helpers.run_json([pgvol, "info", sparse, "--json"])
    assert info["bricks_stored"] < info["bricks_total"]
    assert sparse.stat().st_size < 0.5 * dense.stat().st_size
    chamfer = {}
    for f in (sparse, dense):
        out = f.with_suffix(".glb")
        helpers.run_ok([pgvol, "decode", f, "-o", out, "-q"])
        chamfer[f.name] = helpers.run_json(
            [pgvol, "compare", out, mesh_path("stanford-bunny"), "--json", "--samples", 50000]
        )["chamfer_l1"]
    a, b = chamfer.values()
    assert abs(a - b) <= 0.01 * b, chamfer


def eval_values(pgvol, pgv, points_csv, out_csv):
    """The field values `pgvol eval` gives at the points of `points_csv`."""
    helpers.run_ok([pgvol, "eval", pgv, points_csv, "-o", out_csv, "-q"])
    return np.loadtxt(out_csv, delimiter=",", skiprows=1, dtype=np.float64)[:, 3]


def test_derived_files_are_sparse_like_encoded_ones(pgvol, mesh_path, reference_mesh, work_dir):
    """`pgvol offset` writes a .pgv as `encode` does: sparse bricks at the automatic precision,
    about the size of the encoded file and decoding within its quantisation of the dense result
    near the surface; --dense-file writes every coefficient as f32."""
    folder = work_dir / "ops"
    folder.mkdir(parents=True, exist_ok=True)
    res = 64
    encoded = folder / "spot-derived-encoded.pgv"
    helpers.run_ok([pgvol, "encode", mesh_path("spot"), "-o", encoded, "--res", res, "-q"])
    sparse, dense = folder / "spot-grown.pgv", folder / "spot-grown-dense.pgv"
    spacing = helpers.run_json([pgvol, "info", encoded, "--json"])["header"]["grid"]["spacing"]
    distance = 1.5 * spacing
    for out, extra in [(sparse, []), (dense, ["--dense-file"])]:
        helpers.run_ok(
            [pgvol, "offset", mesh_path("spot"), "-o", out, "--distance", distance, "--res", res, "-q", *extra]
        )
    info = {f: helpers.run_json([pgvol, "info", f, "--json"]) for f in (sparse, dense)}
    assert info[sparse]["header"]["encoding"] == "sparse-bricks"
    assert info[sparse]["precision"] == "fixed"
    assert info[sparse]["bricks_stored"] < info[sparse]["bricks_total"]
    assert info[dense]["header"]["encoding"] == "dense-f32"
    assert dense.stat().st_size > 4 * res**3
    assert sparse.stat().st_size <= 3 * encoded.stat().st_size, (sparse.stat().st_size, encoded.stat().st_size)
    # The band recorded is the one the offset is exact in: the mesh's encoding band.
    band = float(info[sparse]["header"]["metadata"]["band"])
    assert band == pytest.approx(float(info[dense]["header"]["metadata"]["band"]))
    grid_spacing = info[sparse]["header"]["grid"]["spacing"]
    assert band == pytest.approx(4 * grid_spacing, rel=1e-4)
    # Near the offset surface the two files give the same field up to the quantisation.
    ref = reference_mesh("spot")
    rng = np.random.default_rng(3)
    points, faces = trimesh.sample.sample_surface(ref, 3000, seed=3)
    points = points + ref.face_normals[faces] * (distance + rng.uniform(-1.5, 1.5, (len(points), 1)) * grid_spacing)
    csv = folder / "spot-derived-points.csv"
    np.savetxt(csv, points, delimiter=",", fmt="%.9g")
    want = eval_values(pgvol, dense, csv, folder / "spot-derived-dense.csv")
    got = eval_values(pgvol, sparse, csv, folder / "spot-derived-sparse.csv")
    near = np.abs(want) < band - 2 * grid_spacing
    assert near.mean() > 0.5
    assert np.abs(got - want)[near].max() < 0.01 * grid_spacing
    # A mesh output has no coefficients to write densely.
    refused = helpers.run([pgvol, "offset", mesh_path("spot"), "-o", folder / "x.glb", "--distance", distance, "--dense-file"])
    assert refused.returncode != 0 and "--dense-file" in refused.stderr, refused.stderr


def parse_cli_ascii(text: str):
    """[(height, [(direction, points)])] from an ASCII Common Layer Interface file."""
    layers = []
    geometry = text.split("$$GEOMETRYSTART", 1)[1]
    for line in geometry.splitlines():
        if line.startswith("$$LAYER/"):
            layers.append((float(line[8:]), []))
        elif line.startswith("$$POLYLINE/"):
            values = line[11:].split(",")
            part, direction, count = (int(v) for v in values[:3])
            assert part == 1 and len(values) == 3 + 2 * count
            points = np.asarray(values[3:], dtype=np.float64).reshape(count, 2)
            layers[-1][1].append((direction, points))
    return layers


def parse_cli_binary(data: bytes):
    """The same from a binary CLI file: commands 127 (layer, float32 z) and 130 (polyline,
    int32 part, direction, count, then float32 x, y pairs), little-endian."""
    end = data.index(b"$$HEADEREND") + len(b"$$HEADEREND")
    header, body = data[:end].decode("ascii"), memoryview(data)[end:]
    assert "$$BINARY" in header
    layers, at = [], 0
    while at < len(body):
        command = int(np.frombuffer(body[at : at + 2], "<u2")[0])
        at += 2
        if command == 127:
            layers.append((float(np.frombuffer(body[at : at + 4], "<f4")[0]), []))
            at += 4
        elif command == 130:
            part, direction, count = (int(v) for v in np.frombuffer(body[at : at + 12], "<i4"))
            at += 12
            assert part == 1
            points = np.frombuffer(body[at : at + 8 * count], "<f4").reshape(count, 2)
            at += 8 * count
            layers[-1][1].append((direction, points.astype(np.float64)))
        else:
            raise AssertionError(f"unknown command {command} at byte {end + at - 2}")
    return header, layers


def test_cli_files_ascii_and_binary_hold_the_json_layers(pgvol, mesh_path, reference_mesh, work_dir):
    ref = reference_mesh("spot")
    layer = float(ref.bounds[1][2] - ref.bounds[0][2]) / 20
    folder = work_dir / "ops"
    folder.mkdir(parents=True, exist_ok=True)
    outs = {"json": folder / "spot.json", "ascii": folder / "spot.cli", "binary": folder / "spot-bin.cli"}
    base = [pgvol, "slice", mesh_path("spot"), "--layer-height", layer, "--res", 96, "-q"]
    helpers.run_ok(base + ["-o", outs["json"]])
    helpers.run_ok(base + ["-o", outs["ascii"]])
    helpers.run_ok(base + ["-o", outs["binary"], "--binary"])
    want = json.loads(outs["json"].read_text())["layers"]
    header, binary = parse_cli_binary(outs["binary"].read_bytes())
    assert f"$$LAYERS/{len(want)}" in header
    for parsed in (parse_cli_ascii(outs["ascii"].read_text()), binary):
        assert len(parsed) == len(want)
        assert sum(len(loops) for _, loops in parsed) > 0
        for (height, loops), w in zip(parsed, want):
            assert abs(height - w["height"]) <= 1e-6 * abs(w["height"]) + 1e-9
            assert len(loops) == len(w["loops"])
            for (direction, points), wl in zip(loops, w["loops"]):
                assert direction == (0 if wl["hole"] else 1)
                expected = np.asarray(wl["points"] + wl["points"][:1], dtype=np.float64)
                np.testing.assert_allclose(points, expected, rtol=1e-6, atol=1e-9)


def test_binary_flag_needs_a_cli_output(pgvol, mesh_path, work_dir):
    out = work_dir / "ops" / "wrong.svg"
    result = helpers.run([pgvol, "slice", mesh_path("spot"), "-o", out, "--layer-height", 0.1, "--binary"])
    assert result.returncode != 0 and "--binary" in result.stderr
    assert not out.exists()


@pytest.mark.parametrize("spacings", [-5, -9])
def test_offsets_from_a_wide_band_file_match_offsets_from_the_mesh(spacings, pgvol, mesh_path, work_dir):
    """A file encoded with --band 12 holds the distance 12 spacings deep: offsetting it agrees
    with offsetting the mesh itself, well inside that band."""
    folder = work_dir / "ops"
    folder.mkdir(parents=True, exist_ok=True)
    wide = folder / "spot-band12.pgv"
    if not wide.exists():
        helpers.run_ok([pgvol, "encode", mesh_path("spot"), "-o", wide, "--res", 96, "--band", 12, "-q"])
    spacing = helpers.run_json([pgvol, "info", wide, "--json"])["header"]["grid"]["spacing"]
    distance = spacings * spacing
    from_file, from_mesh = folder / f"spot-file{spacings}.ply", folder / f"spot-mesh{spacings}.ply"
    helpers.run_ok([pgvol, "offset", wide, "-o", from_file, "--distance", distance, "-q"])
    helpers.run_ok([pgvol, "offset", mesh_path("spot"), "-o", from_mesh, "--distance", distance, "--res", 96, "-q"])
    report = helpers.run_json([pgvol, "compare", from_file, from_mesh, "--samples", 50000, "--json"])
    assert report["hausdorff_pct"] < 0.1, report["hausdorff_pct"]


def test_a_drain_outside_the_cavity_is_refused(pgvol, tmp_path):
    """A drain whose point is not in the cavity would open nothing: refused, naming the drain."""
    spot = helpers.shared_meshes_dir() / "spot.obj"
    reference = helpers.load_input(spot)
    inside = reference.bounds.mean(axis=0)
    outside = reference.bounds[1] + 0.5
    out = tmp_path / "hollow.glb"
    for point, ok in [(inside, True), (outside, False)]:
        drain = ",".join(f"{c}" for c in [*point, 0, 0, 1, 0.1])
        r = helpers.run(
            [pgvol, "shell", spot, "-o", out, "--thickness", 0.05, "--hollow", "--drain", drain, "--res", 96],
            timeout=300,
        )
        if ok:
            assert r.returncode == 0, r.describe()
        else:
            assert r.returncode == 1 and "drain 1" in r.stderr and "outside the shape" in r.stderr, r.describe()


def test_hollowing_that_would_change_nothing_is_refused(pgvol, tmp_path):
    """A drain narrower than the grid resolves would leave the cavity sealed, and walls thicker
    than half the part leave no cavity: both refused, with what would work, where the result
    would otherwise be the solid unchanged. trimesh confirms the accepted drain opens the cavity
    (one piece) where the unresolved one would not."""
    spot = helpers.shared_meshes_dir() / "spot.obj"
    inside = helpers.load_input(spot).bounds.mean(axis=0)
    out = tmp_path / "hollow.obj"
    base = [pgvol, "shell", spot, "-o", out, "--hollow", "--res", 48]
    drain = lambda d: ",".join(f"{c}" for c in [*inside, 0, 0, -1, d])  # noqa: E731
    r = helpers.run([*base, "--thickness", 0.1, "--drain", drain(0.001)], timeout=300)
    assert r.returncode == 1 and "drain 1's diameter" in r.stderr and "--res" in r.stderr, r.describe()
    assert not out.exists()
    r = helpers.run([*base, "--thickness", 5], timeout=300)
    assert r.returncode == 1 and "leave no cavity" in r.stderr, r.describe()
    helpers.run_ok([*base, "--thickness", 0.1, "--drain", drain(0.2), "-q"])
    assert len(trimesh.load(out, force="mesh").split(only_watertight=False)) == 1


def test_an_offset_beyond_the_reach_says_what_would_hold_it(pgvol, mesh_path, tmp_path):
    """Beyond the file's exact reach the refusal names the encode that would hold it; beyond
    the grid's box, where no band would, it says so instead of naming an absurd band."""
    pgv = tmp_path / "spot.pgv"
    helpers.run_ok([pgvol, "encode", mesh_path("spot"), "-o", pgv, "--res", 48, "-q"])
    out = tmp_path / "o.obj"
    r = helpers.run([pgvol, "offset", pgv, "-o", out, "--distance", 0.5])
    assert r.returncode == 1 and "pgvol encode MESH --band" in r.stderr, r.describe()
    for far in ("1e30", "-50"):
        r = helpers.run([pgvol, "offset", pgv, "-o", out, f"--distance={far}"])
        assert r.returncode == 1 and "reaches beyond the field's grid" in r.stderr, r.describe()
        assert "--band" not in r.stderr and not out.exists(), r.describe()


def test_an_offset_lost_between_nodes_names_the_grid(pgvol, tmp_path):
    """Shrinking a 0.5-thick plate by 0.05 leaves 0.4, which a grid of spacing 0.43 misses: the
    refusal names the spacing and a finer grid, and that grid holds the plate (trimesh: two
    faces 0.4 apart)."""
    plate = tmp_path / "plate.stl"
    trimesh.creation.box(extents=[0.5, 50, 50]).export(plate)
    out = tmp_path / "o.stl"
    r = helpers.run([pgvol, "offset", plate, "-o", out, "--distance=-0.05"], timeout=300)
    assert r.returncode == 1 and "the result is empty" in r.stderr, r.describe()
    assert "spacing 0.433" in r.stderr and "--res" in r.stderr and not out.exists(), r.describe()
    helpers.run_ok([pgvol, "offset", plate, "-o", out, "--distance=-0.05", "--res", 512, "-q"])
    thickness = np.ptp(trimesh.load(out).vertices[:, 0])
    assert abs(thickness - 0.4) < 0.03, thickness


def test_info_shows_the_reach_offsets_may_use(pgvol, mesh_path, tmp_path):
    """`--band W` keeps exact distances for offsets to W − 2 spacings: `info` says so, and an
    offset just inside that reach is accepted, one just beyond it refused."""
    pgv = tmp_path / "spot-band6.pgv"
    helpers.run_ok([pgvol, "encode", mesh_path("spot"), "-o", pgv, "--res", 48, "--band", 6, "-q"])
    info = helpers.run_json([pgvol, "info", pgv, "--json"])
    spacing = info["header"]["grid"]["spacing"]
    reach = info["exact_reach"]
    assert abs(reach - 4 * spacing) <= 1e-4 * spacing, (reach, spacing)
    text = helpers.run_ok([pgvol, "info", pgv]).stdout
    assert "exact reach" in text and "(4.00 spacings)" in text, text
    out = tmp_path / "spot-band6-offset.pgv"
    helpers.run_ok([pgvol, "offset", pgv, "-o", out, "--distance", 0.95 * reach, "-q"])
    refused = helpers.run([pgvol, "offset", pgv, "-o", out, "--distance", 1.05 * reach])
    assert refused.returncode != 0 and "--band" in refused.stderr, refused.stderr
