import numpy as np
import pytest
import trimesh

from app import objects
from app.nift.raycast import cast, make_scene, signed_distance

SEEDS = range(8)


@pytest.mark.parametrize("category", objects.CATEGORIES)
def test_instances_are_watertight_upright_and_in_range(category):
    for seed in SEEDS:
        mesh = objects.generate(category, seed)
        sem = objects.semantics(mesh)
        assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
        assert abs(mesh.bounds[0, 2]) < 1e-9, "rests on z = 0"
        assert np.isclose(mesh.bounds[1, 2], sem.height, atol=1e-6)
        for name, (lo, hi) in objects.RANGES[category].items():
            assert lo <= sem.params[name] <= hi, f"{category} {seed} {name}"
        # axis of revolution on z: the body (ignoring a +x handle) is symmetric about it
        assert np.isclose(mesh.bounds[0, 1], -mesh.bounds[1, 1], atol=1e-3)


@pytest.mark.parametrize("category", objects.CATEGORIES)
def test_generation_is_deterministic_and_seeds_differ(category):
    a, b, c = objects.generate(category, 3), objects.generate(category, 3), objects.generate(category, 4)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    assert objects.semantics(a).params != objects.semantics(c).params
    a.apply_translation([1, 0, 0])  # callers get copies: the cache is untouched
    assert np.array_equal(objects.generate(category, 3).vertices, b.vertices)


def test_splits_are_disjoint_and_validated():
    for category in objects.CATEGORIES:
        train, test = set(objects.split(category, "train")), set(objects.split(category, "test"))
        assert train and test and not train & test
    with pytest.raises(ValueError, match="unknown object category 'teapot'"):
        objects.generate("teapot", 0)
    with pytest.raises(ValueError, match="unknown split"):
        objects.split("mug", "val")


def test_mug_handle_hole_is_open_and_peg_sized():
    for seed in SEEDS:
        mesh = objects.generate("mug", seed)
        sem = objects.semantics(mesh)
        assert mesh.euler_number == 0, "a mug with a handle has genus 1"
        scene = make_scene(mesh.vertices, mesh.faces)
        c = np.array(sem.handle_center)
        axis = np.array(sem.handle_axis)
        assert signed_distance(scene, c[None])[0] > objects.fixtures.RACK_PEG_RADIUS
        # rays along the hole axis at the centre and one peg radius around it pass through
        offsets = [np.zeros(3)] + [objects.fixtures.RACK_PEG_RADIUS * v for v in np.eye(3) if abs(v @ axis) < 0.5]
        origins = np.array([c + o - 0.2 * axis for o in offsets])
        rays = np.concatenate([origins, np.tile(axis, (len(origins), 1))], axis=1)
        assert np.isinf(cast(scene, rays)).all(), f"mug {seed}: handle hole blocked"


def test_semantic_landmarks_match_the_geometry():
    for seed in SEEDS:
        mug = objects.generate("mug", seed)
        sem = objects.semantics(mug)
        scene = make_scene(mug.vertices, mug.faces)
        # from the axis, just below the rim, the first wall is at the rim's inner radius
        ray = np.array([[0, 0, sem.rim_height - 0.002, 0, -1, 0]])
        assert np.isclose(cast(scene, ray)[0], sem.rim_inner_radius, atol=1e-3)

        bottle = objects.generate("bottle", seed)
        bs = objects.semantics(bottle)
        lo, hi = bs.neck_range
        assert lo < bs.neck_height < hi <= bs.height
        ray = np.array([[0.2, 0, bs.neck_height, -1, 0, 0]])  # from outside towards the axis
        hit = cast(make_scene(bottle.vertices, bottle.faces), ray)[0]
        assert np.isclose(0.2 - hit, bs.neck_radius, atol=1e-3)


def test_fixtures():
    rack, shelf = objects.rack(), objects.shelf()
    assert rack.mesh.is_watertight and shelf.mesh.is_watertight
    d = np.array(rack.landmarks["peg_direction"])
    assert np.isclose(np.degrees(np.arcsin(d[2])), 45.0)
    tip = np.array(rack.landmarks["peg_tip"])
    assert abs(signed_distance(make_scene(rack.mesh.vertices, rack.mesh.faces), tip[None])[0]) < 1e-4
    assert np.isclose(shelf.mesh.bounds[1, 2], shelf.landmarks["top_center"][2])
    with pytest.raises(ValueError, match="unknown fixture"):
        objects.fixture("table")


def test_load_mesh_accepts_good_files_and_names_the_problem(tmp_path):
    bowl = objects.generate("bowl", 1)
    for ext in ("obj", "stl", "ply", "glb"):
        path = tmp_path / f"bowl.{ext}"
        bowl.export(path)
        loaded = objects.load_mesh(path)
        assert loaded.is_watertight and np.isclose(loaded.volume, bowl.volume, rtol=1e-4)
    open_box = trimesh.creation.box()
    open_box.faces = open_box.faces[:-2]  # one side missing: a hole the repair closes
    open_box.export(tmp_path / "open.stl")
    assert np.isclose(objects.load_mesh(tmp_path / "open.stl").volume, 1.0)
    trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]]).export(tmp_path / "triangle.stl")
    with pytest.raises(ValueError, match="cannot be a solid object"):
        objects.load_mesh(tmp_path / "triangle.stl")
    with pytest.raises(FileNotFoundError, match="no such mesh file"):
        objects.load_mesh(tmp_path / "missing.obj")
    (tmp_path / "cloud.xyz").write_text("0 0 0\n")
    with pytest.raises(ValueError, match="unsupported mesh format"):
        objects.load_mesh(tmp_path / "cloud.xyz")
    (tmp_path / "junk.ply").write_text("not a mesh")
    with pytest.raises(ValueError, match="could not read"):
        objects.load_mesh(tmp_path / "junk.ply")
    shifted = bowl.copy()
    shifted.apply_translation([0.3, -0.2, 0.5])
    shifted.export(tmp_path / "shifted.obj")
    upright = objects.load_mesh(tmp_path / "shifted.obj", upright=True)  # a bowl: its footprint centre is its axis
    assert np.allclose(upright.bounds[0, 2], 0.0) and np.allclose(upright.bounds.mean(axis=0)[:2], 0.0, atol=1e-4)
