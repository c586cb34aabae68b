"""Contouring, offsets, shells, slices and comparisons, checked with trimesh's measurements of
the results."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import pgvol
from conftest import near_surface_points


@pytest.mark.parametrize("method", ["mc", "sn", "dc"])
def test_contours_are_watertight_and_enclose_the_volume_of_the_mesh(
    spot_field, spot_trimesh, method
):
    v, t = spot_field.to_mesh(method=method)
    out = trimesh.Trimesh(v, t, process=False)
    assert out.is_watertight and out.is_winding_consistent
    assert out.volume > 0  # counter-clockwise seen from outside
    assert out.volume == pytest.approx(spot_trimesh.volume, rel=0.01)
    # Every vertex lies on the source surface, within a small part of a spacing.
    _, distance, _ = trimesh.proximity.closest_point(spot_trimesh, v[::7])
    assert np.median(distance) < 0.02 * spot_field.grid.spacing
    assert np.percentile(distance, 99) < 0.2 * spot_field.grid.spacing


def test_to_trimesh_and_from_trimesh(spot_field, spot_trimesh):
    mesh = spot_field.to_trimesh(method="dc")
    assert isinstance(mesh, trimesh.Trimesh) and mesh.is_watertight
    v, t = spot_field.to_mesh(method="dc")
    assert np.array_equal(mesh.vertices, v) and np.array_equal(mesh.faces, t)
    f = pgvol.Field.from_trimesh(spot_trimesh, res=96)
    assert f.to_bytes() == spot_field.to_bytes()
    coarse = pgvol.Field.from_trimesh(mesh, voxel=0.05)
    assert coarse.grid.spacing == pytest.approx(0.05, rel=0.02)


def test_resampled_and_offset_levels(spot_field, spot_trimesh):
    fine_v, _ = spot_field.to_mesh(res=128)
    coarse_v, _ = spot_field.to_mesh()
    assert len(fine_v) > 1.5 * len(coarse_v)
    d = 0.5 * spot_field.exact_band
    grown = spot_field.offset(d)
    points = near_surface_points(spot_trimesh, 500, 0.5 * spot_field.exact_band, seed=9)
    keep = spot_field.is_exact(points) & grown.is_exact(points)
    np.testing.assert_allclose(grown(points)[keep], spot_field(points)[keep] - d, atol=1e-5)
    # The offset surface and the level set `iso=d` are the same surface.
    level = trimesh.Trimesh(*spot_field.to_mesh(iso=d), process=False)
    offset = trimesh.Trimesh(*grown.to_mesh(), process=False)
    assert level.volume == pytest.approx(offset.volume, rel=1e-4)
    assert level.volume > spot_trimesh.volume + 0.9 * d * spot_trimesh.area
    shrunk = trimesh.Trimesh(*spot_field.offset(-d).to_mesh(), process=False)
    assert shrunk.volume < spot_trimesh.volume - 0.9 * d * spot_trimesh.area


def test_shells_and_hollowing(spot, spot_trimesh, tmp_path):
    f = pgvol.Field.from_mesh(*spot, res=96, band=8)
    thickness = 3 * f.grid.spacing
    hollow = f.shell(thickness, hollow=True)
    kind, amount = hollow.metadata["operation"].split()
    assert kind == "hollow" and float(amount) == pytest.approx(thickness, rel=1e-6)
    solid = trimesh.Trimesh(*hollow.to_mesh(), process=False)
    assert solid.is_watertight and solid.body_count == 2
    # The cavity is the part of the solid deeper than the wall: its volume estimated from
    # random points inside (the field's sign, checked against trimesh in test_distance) by
    # their distance to the surface from trimesh's closest points.
    rng = np.random.default_rng(10)
    lo, hi = spot_trimesh.bounds
    points = rng.uniform(lo, hi, (20000, 3))
    inside = f(points) < 0
    _, depth, _ = trimesh.proximity.closest_point(spot_trimesh, points[inside])
    cavity = np.sum(depth > thickness) / len(points) * np.prod(hi - lo)
    assert spot_trimesh.volume - solid.volume == pytest.approx(cavity, rel=0.05)
    # Points deeper than the wall are now outside the solid.
    points = points[:4000]
    depth = -f(points)
    cavity = depth > thickness + f.grid.spacing
    assert cavity.sum() > 100
    assert np.all(hollow(points[cavity]) > 0)
    wall = (depth > f.grid.spacing) & (depth < thickness - f.grid.spacing)
    assert np.all(hollow(points[wall]) < 0)
    outer = trimesh.Trimesh(*f.shell(thickness, side="outer").to_mesh(), process=False)
    assert outer.volume > solid.volume
    # Derived fields are saved sparse and quantised, as the command-line tool saves them, with
    # the band they are exact in (the field's less the wall, which the hollowing reads).
    path = tmp_path / "hollow.pgv"
    hollow.save(path)
    assert hollow.band == pytest.approx(f.band - thickness, rel=1e-5)
    assert path.stat().st_size < len(hollow.to_bytes(dense=True)) / 4
    loaded = pgvol.Field.load(path)
    assert loaded.band == pytest.approx(hollow.band) and loaded.metadata["operation"] == "hollow " + amount
    near = near_surface_points(solid, 2000, loaded.band - 2 * f.grid.spacing, seed=11)
    keep = np.abs(hollow(near)) < loaded.band - 2 * f.grid.spacing
    assert keep.mean() > 0.5
    assert np.abs(loaded(near) - hollow(near))[keep].max() < 0.01 * f.grid.spacing
    # Saving the loaded field gives the same file.
    assert loaded.to_bytes() == path.read_bytes()


def test_drain_holes_open_the_cavity(spot):
    f = pgvol.Field.from_mesh(*spot, res=96, band=8)
    thickness = 3 * f.grid.spacing
    closed = f.shell(thickness, hollow=True)
    # A point deep inside the body and a hole going down through the belly.
    lo, hi = f.bounds
    centre = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2]
    point = np.array(centre, dtype=np.float64)
    assert f(point[None])[0] < -2 * thickness
    drained = f.shell(thickness, hollow=True, drains=[(tuple(point), (0, 0, -1), 0.1)])
    flat = f.shell(thickness, hollow=True, drains=[[*point, 0, 0, -1, 0.1]])
    assert drained.to_bytes(dense=True) == flat.to_bytes(dense=True)
    one = trimesh.Trimesh(*drained.to_mesh(), process=False)
    two = trimesh.Trimesh(*closed.to_mesh(), process=False)
    assert two.body_count == 2 and one.body_count == 1
    with pytest.raises(ValueError, match="its point must be in the cavity"):
        f.shell(thickness, hollow=True, drains=[((0, 0, 10), (0, 0, 1), 0.1)])
    with pytest.raises(ValueError, match="expected seven finite numbers"):
        f.shell(thickness, hollow=True, drains=[(1, 2)])
    with pytest.raises(ValueError, match="a drain is"):
        f.shell(thickness, hollow=True, drains=["north"])


def test_slices_have_the_area_of_trimesh_cross_sections(spot_field, spot_trimesh):
    h = 0.05
    layers = spot_field.slice(layer_height=h)
    lo, hi = spot_trimesh.bounds
    assert len(layers) == int(np.floor((hi[2] - lo[2] - h / 2) / h)) + 1
    assert layers[0].height == pytest.approx(lo[2] + h / 2, abs=1e-5)
    for layer in layers[1:-1:3]:
        assert len(layer.loops) == len(layer.holes) > 0
        area = 0.0
        for loop, hole in zip(layer.loops, layer.holes):
            assert loop.dtype == np.float32 and loop.shape[1] == 2
            x, y = loop[:, 0].astype(np.float64), loop[:, 1].astype(np.float64)
            signed = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
            assert (signed < 0) == hole  # holes clockwise, outer loops counter-clockwise
            area += signed
        reference = section_area(spot_trimesh, layer.height)
        assert area == pytest.approx(reference, rel=0.02, abs=4 * spot_field.grid.spacing**2)
    x_layers = spot_field.slice(0.2, axis="x")
    assert x_layers[0].height == pytest.approx(lo[0] + 0.1, abs=1e-5)


def section_area(mesh, z):
    """The area of a closed mesh's cross-section at height z, from trimesh's plane
    intersection segments: each segment oriented with the solid on its left (its face's normal
    on its right) and summed by Green's theorem."""
    lines, faces = trimesh.intersections.mesh_plane(
        mesh, plane_normal=(0, 0, 1), plane_origin=(0, 0, z), return_faces=True
    )
    a, b = lines[:, 0, :2], lines[:, 1, :2]
    d = b - a
    n = mesh.face_normals[faces][:, :2]
    flip = d[:, 1] * n[:, 0] - d[:, 0] * n[:, 1] < 0
    a[flip], b[flip] = b[flip].copy(), a[flip].copy()
    return 0.5 * np.sum(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1])


def test_compare_agrees_with_trimesh_closest_points(spot_field, spot_trimesh):
    v, t = spot_field.to_mesh(method="mc")
    result = pgvol.compare((v, t), spot_trimesh, samples=20000, seed=3)
    assert isinstance(result, pgvol.Comparison)
    assert result.a.watertight and result.b.watertight
    assert result.b.triangles == len(spot_trimesh.faces)
    assert result.b.volume == pytest.approx(spot_trimesh.volume, rel=1e-6)
    samples, _ = trimesh.sample.sample_surface(trimesh.Trimesh(v, t, process=False), 20000, seed=3)
    _, distance, _ = trimesh.proximity.closest_point(spot_trimesh, samples)
    assert result.mean_a_to_b == pytest.approx(distance.mean(), rel=0.1)
    assert result.hausdorff >= 0.9 * distance.max()
    assert result.hausdorff < 0.5 * spot_field.grid.spacing
    assert len(result.depth_buffer.views) == 14
    assert result.vertex_deviation.vertices == result.a.vertices
    assert "watertight=True" in repr(result.a)
    again = pgvol.compare((v, t), spot_trimesh, samples=20000, seed=3)
    assert again == result
    with pytest.raises(ValueError, match="samples must be positive"):
        pgvol.compare((v, t), spot_trimesh, samples=0)


def test_slice_file_gives_the_layers_of_the_loaded_field(spot_field, spot_trimesh, tmp_path):
    path = tmp_path / "spot.pgv"
    spot_field.save(path)
    h = 0.05
    streamed = pgvol.slice_file(path, h)
    loaded = pgvol.Field.load(path).slice(h)
    assert len(streamed) == len(loaded) > 10
    for a, b in zip(streamed, loaded):
        assert a.height == b.height and a.holes == b.holes and len(a.loops) > 0
        assert all(np.array_equal(p, q) for p, q in zip(a.loops, b.loops, strict=True))
    middle = streamed[len(streamed) // 2]
    area = 0.0
    for loop in middle.loops:
        x, y = loop[:, 0].astype(np.float64), loop[:, 1].astype(np.float64)
        area += 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    reference = section_area(spot_trimesh, middle.height)
    assert area == pytest.approx(reference, rel=0.02, abs=4 * spot_field.grid.spacing**2)
    across = pgvol.slice_file(path, 0.2, axis="x", tolerance=0.01)
    assert [layer.height for layer in across] == [
        layer.height for layer in spot_field.slice(0.2, axis="x", tolerance=0.01)
    ]
    with pytest.raises(pgvol.MissingFileError, match="nowhere.pgv"):
        pgvol.slice_file(tmp_path / "nowhere.pgv", h)
    with pytest.raises(pgvol.ParameterError):
        pgvol.slice_file(path, 0.0)
    cut = tmp_path / "cut.pgv"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(pgvol.InputFileError, match="cut.pgv"):
        pgvol.slice_file(cut, h)
