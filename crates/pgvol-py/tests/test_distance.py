"""Values and gradients against trimesh's signed distance and closest points, computed from
the same mesh by code that is not pgvol's."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import pgvol
from conftest import near_surface_points


def test_values_are_trimesh_signed_distances_with_the_sign_flipped(spot_field, spot_trimesh):
    f = spot_field
    h = f.grid.spacing
    points = near_surface_points(spot_trimesh, 1500, f.exact_band, seed=1)
    # trimesh's signed distance is positive inside; pgvol's is negative inside.
    reference = -trimesh.proximity.signed_distance(spot_trimesh, points)
    values = f(points)
    assert values.shape == (1500,) and values.dtype == np.float32
    exact = f.is_exact(points)
    assert exact.mean() > 0.95
    error = np.abs(values - reference)[exact]
    assert error.max() < 0.15 * h, error.max() / h
    assert np.sqrt(np.mean(error**2)) < 0.03 * h
    # Inside and outside agree everywhere, exact or clamped.
    clear = np.abs(reference) > 0.05 * h
    assert np.array_equal(np.sign(values[clear]), np.sign(reference[clear]))


def test_far_values_keep_the_sign_of_trimesh_containment(spot_field, spot_trimesh):
    rng = np.random.default_rng(2)
    lo, hi = spot_trimesh.bounds
    points = rng.uniform(lo, hi, (1000, 3))
    inside = spot_trimesh.contains(points)
    values = spot_field(points)
    _, distance, _ = trimesh.proximity.closest_point(spot_trimesh, points)
    clear = distance > spot_field.grid.spacing
    assert clear.sum() > 700 and inside[clear].sum() > 100
    assert np.array_equal(values[clear] < 0, inside[clear])
    # Beyond the band the magnitude is a clamp, not a distance.
    assert not spot_field.is_exact(points[clear & (np.abs(values) > 2 * spot_field.exact_band)]).any()


def test_gradients_point_away_from_trimesh_closest_points(spot_field, spot_trimesh):
    f = spot_field
    h = f.grid.spacing
    points = near_surface_points(spot_trimesh, 1500, f.exact_band, seed=3)
    closest, distance, _ = trimesh.proximity.closest_point(spot_trimesh, points)
    values, gradients = f.eval_with_gradient(points)
    assert gradients.shape == (1500, 3) and gradients.dtype == np.float32
    keep = f.is_exact(points) & (distance > 0.3 * h)
    direction = (points - closest) / distance[:, None] * np.sign(values)[:, None]
    unit = gradients / np.linalg.norm(gradients, axis=1)[:, None]
    cosine = np.sum(unit * direction, axis=1)[keep]
    assert np.median(cosine) > 0.999
    assert np.percentile(cosine, 5) > 0.95
    assert np.percentile(np.abs(np.linalg.norm(gradients[keep], axis=1) - 1), 95) < 0.05


def test_gradients_are_the_derivative_of_the_values(spot_field, spot_trimesh):
    """Analytic gradients against central differences of the values (float64 steps)."""
    f = spot_field
    points = near_surface_points(spot_trimesh, 500, f.exact_band, seed=4)
    _, gradients = f.eval_with_gradient(points)
    step = 0.05 * f.grid.spacing
    numeric = np.stack(
        [
            (f(points + step * e).astype(np.float64) - f(points - step * e)) / (2 * step)
            for e in np.eye(3)
        ],
        axis=1,
    )
    assert np.percentile(np.abs(numeric - gradients), 99) < 0.01


def test_values_with_and_without_gradients_agree(spot_field, spot_trimesh):
    points = near_surface_points(spot_trimesh, 2000, 0.2, seed=5)
    values, _ = spot_field.eval_with_gradient(points)
    np.testing.assert_allclose(spot_field(points), values, rtol=1e-6, atol=1e-7)


def test_points_without_a_place_are_refused_not_clamped(spot_field, spot_trimesh):
    """A NaN, infinite or huge coordinate would be clamped into the grid and get the value of
    some other point; every query refuses it, naming the row, as the `eval` command does."""
    good = near_surface_points(spot_trimesh, 4, 0.1, seed=3)
    for bad in (np.nan, np.inf, -1e30):
        points = good.copy()
        points[2, 1] = bad
        for query in (spot_field, spot_field.eval_with_gradient, spot_field.is_exact):
            with pytest.raises(pgvol.ParameterError, match="point 2 "):
                query(points)
    assert np.isfinite(spot_field(good)).all()


def test_a_sphere_is_its_analytic_distance(tmp_path):
    """An icosphere made by trimesh: the field is |p| - r up to the faceting."""
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=1.0)
    f = pgvol.Field.from_mesh(sphere.vertices, sphere.faces, res=64)
    rng = np.random.default_rng(6)
    directions = rng.normal(size=(2000, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    radii = rng.uniform(1 - f.exact_band, 1 + f.exact_band, 2000)
    points = directions * radii[:, None]
    exact = -trimesh.proximity.signed_distance(sphere, points)
    values = f(points)
    keep = f.is_exact(points)
    assert np.abs(values - exact)[keep].max() < 0.15 * f.grid.spacing
    # The facets lie within 0.1 % of the radius: the analytic sphere is close too.
    assert np.abs(values - (radii - 1))[keep].max() < 0.15 * f.grid.spacing + 2e-3
