"""Surfaces through point clouds from Python, and their cross-sections cut from the method's own
field (the RBF interpolant for the RBF methods) rather than from the resampled volume."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import pgvol


def sphere_cloud(n: int) -> np.ndarray:
    """n points spread evenly (Fibonacci lattice) on the unit sphere; each is its own normal."""
    i = np.arange(n) + 0.5
    y = 1.0 - 2.0 * i / n
    rho = np.sqrt(1.0 - y * y)
    phi = math.pi * (3.0 - math.sqrt(5.0)) * np.arange(n)
    return np.stack([rho * np.cos(phi), y, rho * np.sin(phi)], axis=1)


@pytest.fixture(scope="module")
def cloud():
    return sphere_cloud(3000)


def area(loop: np.ndarray) -> float:
    x, y = loop[:, 0].astype(np.float64), loop[:, 1].astype(np.float64)
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def test_a_field_through_the_points_passes_through_them(cloud):
    field = pgvol.Field.from_points(cloud, cloud, res=48)
    assert isinstance(field, pgvol.Field)
    assert field.grid.dims == (48, 48, 48)
    values = field(cloud)
    assert np.abs(values).max() < 0.1 * field.grid.spacing
    # Inside at the centre (clamped to the band), outside beyond the sphere.
    assert field([[0.0, 0.0, 0.0]])[0] < 0.0 < field([[0.0, 0.0, 1.05]])[0]


def test_sections_are_circles_cut_from_the_rbf(cloud):
    field, layers = pgvol.Field.from_points(
        cloud, cloud, res=64, method="rbf-wendland", sections=("z", [0.5, 0.0])
    )
    assert [layer.height for layer in layers] == [0.0, 0.5]
    # The resampled volume's sections at the same planes, for comparison.
    spacing = field.grid.spacing
    for layer in layers:
        h = layer.height
        r = math.sqrt(1.0 - h * h)
        assert len(layer.loops) == 1 and layer.holes == [False]
        loop = layer.loops[0]
        assert loop.dtype == np.float32 and loop.shape[1] == 2
        circle = math.pi * r * r
        assert abs(area(loop) - circle) < 0.01 * circle
        radii = np.hypot(loop[:, 0], loop[:, 1])
        assert abs(radii.mean() - r) < 1e-3
        assert np.abs(radii - r).max() < 5e-3
        # The written volume is near zero on the section (close surfaces), yet the section is
        # not the volume's own.
        points = np.column_stack([loop, np.full(len(loop), h, dtype=np.float32)])
        assert np.abs(field(points)).max() < 0.05 * spacing
        (other,) = field.slice(1.0, first=h, resolution=spacing)
        assert other.height == pytest.approx(h)
        assert abs(area(other.loops[0]) - area(loop)) < 0.002 * circle
        assert other.loops[0].shape != loop.shape or not np.array_equal(other.loops[0], loop)


def test_every_axis_and_a_finer_resolution(cloud):
    circle = math.pi * 0.75
    for axis in "xyz":
        _, (layer,) = pgvol.Field.from_points(cloud, cloud, res=48, sections=(axis, [-0.5]))
        _, (fine,) = pgvol.Field.from_points(
            cloud, cloud, res=48, sections=(axis, [-0.5]), section_resolution=0.01
        )
        for cut in (layer, fine):
            radii = np.hypot(cut.loops[0][:, 0], cut.loops[0][:, 1])
            assert abs(radii.mean() - math.sqrt(0.75)) < 2e-3, axis
        # Chords simplified to a tenth of 0.01 rather than of the grid spacing (0.047) cut
        # less off the circle.
        coarse_error = circle - area(layer.loops[0])
        fine_error = circle - area(fine.loops[0])
        assert 0 < fine_error < 0.5 * coarse_error, (axis, fine_error, coarse_error)


def test_a_plane_missing_the_surface_warns_and_gives_an_empty_layer(cloud):
    with pytest.warns(pgvol.PgvolWarning, match=r"z = 1\.05 is empty"):
        _, layers = pgvol.Field.from_points(cloud, cloud, res=48, sections=("z", [0.0, 1.05]))
    assert [len(layer.loops) for layer in layers] == [1, 0]


def test_bad_sections_are_refused_by_name(cloud):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for sections, says in [
            (("z", [0.0, 3.0]), "z = 3 is outside the grid box"),
            (("z", [float("nan")]), "not a finite number"),
            (("z", []), "no section heights"),
            (("w", [0.0]), "unknown axis 'w'"),
            ("z:0", "sections must be (axis, heights)"),
        ]:
            with pytest.raises(pgvol.ParameterError) as e:
                pgvol.Field.from_points(cloud, cloud, res=48, sections=sections)
            assert says in str(e.value), str(e.value)
            assert "--" not in str(e.value)
    with pytest.raises(pgvol.ParameterError, match="only with sections"):
        pgvol.Field.from_points(cloud, cloud, res=48, section_resolution=0.1)
    with pytest.raises(pgvol.ParameterError, match="2 normals for 3000 points"):
        pgvol.Field.from_points(cloud, cloud[:2], res=48)
    with pytest.raises(pgvol.ParameterError, match="unknown method"):
        pgvol.Field.from_points(cloud, method="rbf")
    with pytest.raises(pgvol.ParameterError, match="holds no points"):
        pgvol.Field.from_points(np.zeros((0, 3)), res=48)
