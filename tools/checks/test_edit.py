"""`pgvol csg` on analytic primaries, checked against closed-form volumes, trimesh's and
manifold3d's view of the contoured results."""

from __future__ import annotations

import math

import manifold3d

import numpy as np
import pytest

import helpers

RES = 96
VOLUME_TOLERANCE = 0.005
SPHERE_A = "sphere:0,0,0,1"
SPHERE_B = "sphere:1,0,0,1"


def lens_volume(radius: float, distance: float) -> float:
    """Volume shared by two balls of equal radius whose centres lie `distance` apart."""
    return math.pi * (4 * radius + distance) * (2 * radius - distance) ** 2 / 12


@pytest.mark.parametrize("op", ["union", "intersection", "difference"])
def test_two_spheres_match_the_lens_formulas(pgvol, work_dir, op):
    ball = 4 / 3 * math.pi
    lens = lens_volume(1.0, 1.0)
    expected = {"union": 2 * ball - lens, "intersection": lens, "difference": ball - lens}[op]
    out = work_dir / "edit" / f"spheres-{op}.stl"
    out.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok([pgvol, "csg", op, SPHERE_A, SPHERE_B, "-o", out, "--res", RES, "-q"])
    mesh = helpers.load_output(out)
    assert helpers.manifold_ok(helpers.manifold_status(mesh)), op
    assert mesh.is_watertight and mesh.is_winding_consistent
    error = helpers.rel_diff(helpers.signed_volume(mesh), expected)
    assert error <= VOLUME_TOLERANCE, f"{op}: volume off by {error:.4%}"


def seam_angles(mesh) -> np.ndarray:
    """Angles (degrees) between adjacent faces near one side of the seam where the small box
    stands on the large one (x = 0.5, z = 1), away from the boxes' own edges."""
    c = mesh.triangles_center
    near = (c[:, 0] > 0.45) & (c[:, 0] < 0.8) & (c[:, 2] > 0.95) & (c[:, 2] < 1.3) & (np.abs(c[:, 1]) < 0.3)
    pairs = mesh.face_adjacency
    both = near[pairs[:, 0]] & near[pairs[:, 1]]
    assert both.sum() > 100, "too few faces near the seam"
    return np.degrees(mesh.face_adjacency_angles[both])


def test_smooth_union_of_boxes_has_no_sharp_seam(pgvol, work_dir):
    boxes = ["box:0,0,0,1,1,1", "box:0,0,1.4,0.5,0.5,0.5"]
    sharp = work_dir / "edit" / "boxes-sharp.stl"
    smooth = work_dir / "edit" / "boxes-smooth.stl"
    sharp.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok([pgvol, "csg", "union", *boxes, "-o", sharp, "--res", RES, "-q"])
    helpers.run_ok([pgvol, "csg", "union", *boxes, "-o", smooth, "--res", RES, "--radius", 0.2, "-q"])
    sharp_mesh, smooth_mesh = helpers.load_output(sharp), helpers.load_output(smooth)
    for mesh in (sharp_mesh, smooth_mesh):
        assert helpers.manifold_ok(helpers.manifold_status(mesh))
    # The crease: the sharp union turns by 90 degrees over a few faces, the fillet of radius
    # 0.2 (about six grid spacings) by small steps.
    assert seam_angles(sharp_mesh).max() > 40.0
    assert seam_angles(smooth_mesh).max() < 20.0
    # The fillet adds material only in the concave corner: at most the region between the
    # quarter circle and the corner, (1 − π/4) r² per unit length of the 4 m long seam.
    added = helpers.signed_volume(smooth_mesh) - helpers.signed_volume(sharp_mesh)
    assert 0 < added < 2 * (1 - math.pi / 4) * 0.2**2 * 4.0


@pytest.mark.parametrize(
    "args, words",
    [
        (["union", SPHERE_A], ["2 values"]),
        (["union", "sphere:0,0,1", SPHERE_B], ["sphere", "4"]),
        (["union", "plane:0,0,1,0", "plane:1,0,0,0"], ["--box"]),
        (["union", SPHERE_A, SPHERE_B, "--radius", "-1"], ["radius"]),
        (["union", SPHERE_A, "missing.stl"], ["missing.stl"]),
        (["union", SPHERE_A, "torus:0,0,0,1"], ["'torus' is not an analytic solid", "cylinder:"]),
    ],
)
def test_bad_csg_input_is_explained(pgvol, work_dir, args, words):
    out = work_dir / "edit" / "bad.stl"
    out.parent.mkdir(parents=True, exist_ok=True)
    run = helpers.run([pgvol, "csg", *args, "-o", out, "--res", 32])
    assert run.returncode != 0
    text = run.stderr.lower()
    assert "panicked" not in text
    for w in words:
        assert w.lower() in text, run.stderr


def test_repair_removes_a_bump_and_keeps_the_rest(pgvol, work_dir):
    """A unit sphere with a ball of radius 0.3 on top; the mask covers the ball, its base
    crossing the mask's lower face."""
    bumped = work_dir / "edit" / "bumped.stl"
    fixed = work_dir / "edit" / "fixed.stl"
    bumped.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok([pgvol, "csg", "union", SPHERE_A, "sphere:0,0,1,0.3", "-o", bumped, "--res", 64, "-q"])
    mask = "-0.45,-0.45,0.75,0.45,0.45,1.45"
    report = helpers.run_json(
        [pgvol, "repair", bumped, "-o", fixed, f"--mask={mask}", "--face=-z", "--alpha", 0.9, "--res", 64, "--json"]
    )
    assert report["masks"][0]["fit_error"] < 1e-3
    mesh = helpers.load_output(fixed)
    assert helpers.manifold_ok(helpers.manifold_status(mesh))
    v = mesh.vertices
    error = np.abs(np.linalg.norm(v, axis=1) - 1.0)
    inside = (np.abs(v[:, 0]) < 0.45) & (np.abs(v[:, 1]) < 0.45) & (v[:, 2] > 0.75)
    # Before: the bump stands 0.3 proud. After: within 3 % of the radius in the mask, and
    # the rest of the sphere as the encoding left it.
    assert error[inside].max() < 0.03, error[inside].max()
    assert error[~inside].max() < 0.002, error[~inside].max()


def test_liming_blend_is_a_closed_manifold(pgvol, work_dir):
    out = work_dir / "edit" / "liming.stl"
    out.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok(
        [pgvol, "blend", "liming", "plane:1,0,0,0", "plane:0,1,0,0", "--cut", "plane:-1,-1,0,0.6",
         "--box=-1,-1,-1,1,1,1", "-o", out, "--res", 64, "-q"]
    )
    mesh = helpers.load_output(out)
    assert helpers.manifold_ok(helpers.manifold_status(mesh))
    # The rounding removes material from the sharp corner's quadrant: between the chamfer
    # x + y = −0.6 (0.18 per unit length) and nothing.
    side = mesh.bounds[1, 2] - mesh.bounds[0, 2]
    quadrant = (mesh.bounds[1, 0] - mesh.bounds[0, 0]) * (mesh.bounds[1, 1] - mesh.bounds[0, 1]) * side
    removed = quadrant - helpers.signed_volume(mesh)
    assert 0.0 < removed < 0.18 * side


def test_planes_are_cut_at_the_box_given(pgvol, work_dir):
    """Two half-spaces intersected within the box [−1, 1]³ are the quarter of the box behind
    both planes: manifold3d's own intersection of the box with the two half-spaces, in volume
    and bounds, not the grid's wider cube."""
    out = work_dir / "edit" / "quarter.stl"
    out.parent.mkdir(parents=True, exist_ok=True)
    helpers.run_ok(
        [pgvol, "csg", "intersection", "plane:1,0,0,0", "plane:0,1,0,0", "--box=-1,-1,-1,1,1,1",
         "-o", out, "--res", 64, "-q"]
    )
    mesh = helpers.load_output(out)
    reference = manifold3d.Manifold.cube([2, 2, 2], center=True).trim_by_plane([-1, 0, 0], 0)
    reference = reference.trim_by_plane([0, -1, 0], 0)
    assert abs(helpers.signed_volume(mesh) - reference.volume()) < 0.01 * reference.volume()
    lo, hi = reference.bounding_box()[:3], reference.bounding_box()[3:]
    assert np.allclose(mesh.bounds, [lo, hi], atol=0.02), mesh.bounds


def test_denoising_smooths_a_noisy_sphere_inside_the_mask_only(pgvol, work_dir):
    import trimesh

    rng = np.random.default_rng(7)
    ball = trimesh.creation.icosphere(subdivisions=5)
    ball.vertices *= (1 + 0.015 * rng.standard_normal(len(ball.vertices)))[:, None]
    noisy = work_dir / "edit" / "noisy.ply"
    noisy.parent.mkdir(parents=True, exist_ok=True)
    ball.export(noisy)
    plain, smooth = work_dir / "edit" / "noisy.stl", work_dir / "edit" / "denoised.stl"
    helpers.run_ok([pgvol, "remesh", noisy, "-o", plain, "--res", 96, "--field", "decoded", "-q"])
    mask = "--mask=-0.6,-0.6,0.4,0.6,0.6,1.2"
    helpers.run_ok([pgvol, "repair", noisy, "-o", smooth, mask, "--denoise", "--coarse", 12, "--res", 96, "-q"])

    def deviation(path):
        """Mean angle (degrees) between face normals and the sphere's, inside and outside."""
        m = helpers.load_output(path)
        c = m.triangles_center
        radial = c / np.linalg.norm(c, axis=1)[:, None]
        angle = np.degrees(np.arccos(np.clip((m.face_normals * radial).sum(1), -1, 1)))
        inside = (np.abs(c[:, 0]) < 0.6) & (np.abs(c[:, 1]) < 0.6) & (c[:, 2] > 0.4)
        return angle[inside].mean(), angle[~inside].mean()

    (in_before, out_before), (in_after, out_after) = deviation(plain), deviation(smooth)
    assert in_after < 0.6 * in_before, (in_before, in_after)
    assert abs(out_after - out_before) < 0.02 * out_before, (out_before, out_after)


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--mask=5,5,5,6,6,6", "--face=-z"], ["ball.pgv", "mask 5,5,5,6,6,6", "no grid node"]),
        (["--mask=0,0,0,1,1", "--face=-z"], ["mask", "six"]),
        (["--mask=0,0,0,1,1,1", "--face=z"], ["+z"]),
        (["--mask=0,0,0,1,1,1"], ["--face"]),
        (["--mask=-0.5,-0.5,0.5,0.5,0.5,1.1", "--face=-z", "--alpha=-1e30"], ["alpha", "-10 to 10"]),
        (["--mask=-1e7,-1e7,-1e7,1e7,1e7,1e7", "--face=-z"], ["takes in the whole shape"]),
    ],
)
def test_bad_repair_input_is_explained(pgvol, work_dir, extra, words):
    ball = work_dir / "edit" / "ball.pgv"
    ball.parent.mkdir(parents=True, exist_ok=True)
    if not ball.exists():
        helpers.run_ok([pgvol, "csg", "union", SPHERE_A, "sphere:0,0,0.5,0.5", "-o", ball, "--res", 32, "-q"])
    run = helpers.run([pgvol, "repair", ball, "-o", work_dir / "edit" / "bad.pgv", *extra])
    assert run.returncode != 0
    assert "panicked" not in run.stderr.lower()
    for w in words:
        assert w.lower() in run.stderr.lower(), run.stderr
