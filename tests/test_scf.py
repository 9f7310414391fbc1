import numpy as np
import pytest
import trimesh

from app.nift.scf import compute_scf, compute_scf_cloud, real_sph_harm, spherical_basis, spherical_function
from app.objects import generate
from hardware.se3 import make_pose, random_rotations

C0_CONSTANT = 2.0 * np.sqrt(np.pi)  # c_0 of F = 1 with orthonormal Y_0^0 = 1 / (2 sqrt(pi))


def query_points(mesh, n, rng):
    lo, hi = mesh.bounds
    c, h = (lo + hi) / 2, (hi - lo) * 0.75
    return rng.uniform(c - h, c + h, size=(n, 3))


def test_quadrature_makes_the_basis_orthonormal():
    basis = spherical_basis(5)
    Y = real_sph_harm(5, basis.directions.astype(np.float64))
    gram = (basis.weights[:, None] * Y).T @ Y
    assert np.allclose(gram, np.eye(36), atol=1e-6)  # directions are stored as float32
    assert len(basis.directions) == 974


def test_sphere_centre_has_only_c0():
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=0.3)
    scf = compute_scf(sphere, np.zeros((1, 3)))[0]
    assert np.isclose(scf[0], C0_CONSTANT, rtol=1e-3)
    assert np.abs(scf[1:]).max() < 1e-3 * C0_CONSTANT


def test_cube_centre_has_only_cubic_bands():
    # F at a cube's centre has octahedral symmetry: no power in bands 1, 2, 3, 5; band 4 carries it
    scf = compute_scf(trimesh.creation.box(extents=[0.2, 0.2, 0.2]), np.zeros((1, 3)))[0]
    assert np.abs(scf[[1, 2, 3, 5]]).max() < 1e-5
    assert scf[4] > 0.05


def test_spherical_function_definition():
    d = np.array([[1.0, 2.0, 3.0, np.inf], [np.inf, np.inf, np.inf, np.inf]], dtype=np.float32)
    F = spherical_function(d.copy())
    d_min, d_avg = 1.0, 2.0
    assert np.allclose(F[0], [(d_min + d_avg) / (x + d_avg) for x in (1.0, 2.0, 3.0)] + [0.0])
    assert np.all(F[1] == 0.0)  # a point that sees nothing


def test_scf_invariances(rng):
    mesh = generate("mug", 5)
    pts = query_points(mesh, 300, rng)
    base = compute_scf(mesh, pts)

    moved = mesh.copy()
    moved.apply_translation([0.7, -0.3, 1.1])
    assert np.allclose(compute_scf(moved, pts + [0.7, -0.3, 1.1]), base, rtol=1e-3, atol=1e-5)

    for scale in (0.5, 2.0):
        scaled = mesh.copy()
        scaled.apply_scale(scale)
        assert np.allclose(compute_scf(scaled, pts * scale), base, rtol=1e-3, atol=1e-5)

    # rotation: exact in the continuum, up to the documented quadrature error with 974 directions
    for R in random_rotations(3, rng):
        rotated = mesh.copy()
        rotated.apply_transform(make_pose(R))
        err = np.linalg.norm(compute_scf(rotated, pts @ R.T) - base, axis=1) / np.linalg.norm(base, axis=1)
        assert np.median(err) < 0.02 and np.percentile(err, 95) < 0.06


def test_rotation_error_shrinks_with_more_directions(rng):
    mesh = generate("bowl", 2)
    pts = query_points(mesh, 150, rng)
    R = random_rotations(1, rng)[0]
    rotated = mesh.copy()
    rotated.apply_transform(make_pose(R))
    errs = []
    for degree in (17, 53):
        a, b = compute_scf(mesh, pts, degree=degree), compute_scf(rotated, pts @ R.T, degree=degree)
        errs.append(np.median(np.linalg.norm(a - b, axis=1) / np.linalg.norm(a, axis=1)))
    assert errs[1] < errs[0]


def test_points_inside_see_the_inner_surface():
    box = trimesh.creation.box(extents=[0.2, 0.1, 0.3])
    scf = compute_scf(box, np.array([[0.03, 0.01, -0.05]]))[0]
    assert np.all(np.isfinite(scf)) and scf[0] > 0.5 * C0_CONSTANT  # every ray hits: F > 0 all round


def test_order_and_bad_input():
    mesh = generate("bottle", 0)
    assert compute_scf(mesh, np.zeros((4, 3)), order=3).shape == (4, 4)
    with pytest.raises(ValueError, match="NaN"):
        compute_scf(mesh, np.array([[0.0, np.nan, 0.0]]))
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        compute_scf(mesh, np.zeros((4, 2)))
    with pytest.raises(ValueError, match="at least"):
        compute_scf_cloud(np.zeros((3, 3)), np.zeros((1, 3)))


def test_cloud_scf_agrees_with_mesh_scf(rng):
    mesh = generate("mug", 7)
    cloud = mesh.sample(3000, seed=1)
    pts = query_points(mesh, 600, rng)
    from app.nift.raycast import make_scene, signed_distance

    pts = pts[signed_distance(make_scene(mesh.vertices, mesh.faces), pts) > 0.005][:300]
    true, est = compute_scf(mesh, pts), compute_scf_cloud(cloud, pts)
    r2 = 1 - ((est - true) ** 2).sum(0) / ((true - true.mean(0)) ** 2).sum(0)
    assert r2[0] > 0.9 and r2.mean() > 0.7


def test_single_view_cloud_sees_one_side():
    from app.nift.raycast import make_scene, view_cloud

    box = trimesh.creation.box(extents=[0.2, 0.2, 0.2])
    seen = view_cloud(make_scene(box.vertices, box.faces), np.array([1.0, 0.0, 0.0]), np.zeros(3))
    assert len(seen) > 100
    assert np.allclose(seen[:, 0], 0.1, atol=1e-5)  # only the face towards the camera
