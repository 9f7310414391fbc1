import numpy as np
import pytest
import trimesh

from app.nift.ibs import compute_ibs
from app.nift.raycast import make_scene, unsigned_distance
from app.objects import generate, rack


def two_spheres(gap_centres: float = 0.16, radius: float = 0.05):
    a, b = trimesh.creation.icosphere(4, radius), trimesh.creation.icosphere(4, radius)
    a.apply_translation([-gap_centres / 2, 0, 0])
    b.apply_translation([gap_centres / 2, 0, 0])
    return a, b


def distance_gap(a, b, points):
    return np.abs(unsigned_distance(make_scene(a.vertices, a.faces), points)
                  - unsigned_distance(make_scene(b.vertices, b.faces), points))


def test_equal_spheres_bisect_on_the_plane():
    a, b = two_spheres()
    ibs = compute_ibs(a, b, n_points=500, n_samples=1500)
    assert ibs.points.shape == (500, 3)
    assert np.abs(ibs.points[:, 0]).max() < 0.25 * ibs.spacing
    assert np.all(np.linalg.norm(ibs.points - ibs.center, axis=1) <= ibs.radius + 1e-9)


def test_every_ibs_point_is_equidistant_mug_and_rack():
    mug = generate("mug", 1)
    fixture = rack().mesh.copy()
    fixture.apply_translation([0.2, 0.0, -0.15])
    ibs = compute_ibs(mug, fixture, n_points=800, return_polygons=True)
    # a point on a Voronoi ridge is equidistant to two samples; the true surfaces differ from the
    # samples by less than the sample spacing
    assert distance_gap(mug, fixture, ibs.points).max() < ibs.spacing
    assert len(ibs.polygons) > 100 and all(p.shape[1] == 3 for p in ibs.polygons)


def test_importance_sampling_prefers_points_near_the_objects():
    a, b = two_spheres()
    near = compute_ibs(a, b, n_points=400, seed=3)
    uniform = compute_ibs(a, b, n_points=400, seed=3, falloff=1e9)
    assert np.median(near.distances) < 0.9 * np.median(uniform.distances)


def test_point_cloud_inputs(rng):
    a, b = two_spheres()
    ibs = compute_ibs(a.sample(3000, seed=1), b.sample(3000, seed=2), n_points=300)
    assert np.abs(ibs.points[:, 0]).max() < ibs.spacing


def test_bad_inputs_are_named():
    a, b = two_spheres(gap_centres=0.06)  # radii 0.05: they overlap
    with pytest.raises(ValueError, match="overlap"):
        compute_ibs(a, b)
    a, b = two_spheres(gap_centres=0.1005)
    with pytest.raises(ValueError, match="touch"):
        compute_ibs(a, b, min_gap=0.002)
    with pytest.raises(ValueError, match="at least 8"):
        compute_ibs(np.zeros((3, 3)), np.ones((50, 3)))
    with pytest.raises(ValueError, match="NaN"):
        compute_ibs(np.full((50, 3), np.nan), np.ones((50, 3)))
