"""`pgvol.perturb`: spot converted by the perturbation method at a small budget gives a field
whose contour is one closed piece near the input (trimesh measures both), whose function list
reads back as the same field, and whose report says what the loop and the checks did."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import pgvol

BUDGET = 100
RES = 64


@pytest.fixture(scope="module")
def converted(spot, tmp_path_factory):
    listed = tmp_path_factory.mktemp("perturb") / "spot-list.pgv"
    field, report = pgvol.perturb(*spot, max_functions=BUDGET, res=RES, list_path=listed)
    return field, report, listed


def test_the_contour_is_one_closed_piece_near_spot(converted, spot_trimesh):
    field, _, _ = converted
    v, t = field.to_mesh(min_component=0.0)
    out = trimesh.Trimesh(vertices=v, faces=t, process=False)
    out.merge_vertices()
    assert len(out.split(only_watertight=False)) == 1
    assert out.is_watertight
    # The grid spacing is 1.1 x spot's longest extent / 63 (0.03): at 100 functions the
    # contour's vertices lie about half a spacing from spot on average (0.015 measured).
    spacing = field.grid.spacing
    _, distance, _ = trimesh.proximity.closest_point(spot_trimesh, out.vertices[::7])
    assert distance.mean() < 0.75 * spacing, (distance.mean(), spacing)


def test_the_report_and_the_metadata_say_what_was_built(converted):
    field, report, _ = converted
    assert isinstance(report, pgvol.PerturbReport)
    loop = report.perturbation
    assert 0 < loop.loop_functions <= BUDGET
    assert loop.history == sorted(loop.history, reverse=True)
    assert loop.stop in ("tolerance", "max_functions", "no_improvement")
    assert report.strays.pieces_left == 0
    assert report.cleanup.wrong_after <= report.cleanup.wrong_before
    assert field.metadata["source"] == "perturbation"
    assert field.grid.dims == (RES, RES, RES)


def test_the_function_list_reads_back_as_the_same_field(converted, spot_trimesh):
    field, _, listed = converted
    back = pgvol.Field.load(listed)
    points = np.asarray(spot_trimesh.sample(500, seed=3), dtype=np.float32)
    assert np.array_equal(back(points), field(points))


def test_bad_options_are_refused(spot):
    with pytest.raises(pgvol.ParameterError, match="at least 1"):
        pgvol.perturb(*spot, max_functions=0)
    with pytest.raises(pgvol.ParameterError, match="tolerance"):
        pgvol.perturb(*spot, tolerance=-1.0)
