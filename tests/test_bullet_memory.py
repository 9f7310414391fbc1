"""PyBullet clients of ours do not keep the meshes they loaded once disconnected (docs/limits.md, "Soak")."""
import subprocess
import sys
import textwrap

ROUNDS = textwrap.dedent("""
    import sys, pathlib, numpy as np, trimesh
    from app.bench.memory import resident_mb
    from hardware.bullet import connect, p
    out, plain = pathlib.Path(sys.argv[1]), sys.argv[2] == "plain"
    rng = np.random.default_rng(0)
    paths = [out / f"{i}.obj" for i in range(48)]
    for path in paths:  # written first, so that only the loading is measured
        mesh = trimesh.creation.icosphere(subdivisions=4)
        mesh.vertices *= rng.uniform(0.5, 1.5, 3)
        mesh.export(path)
    sizes = []
    for r in range(6):
        client = p.connect(p.DIRECT) if plain else connect()
        for path in paths[8 * r:8 * (r + 1)]:  # 8 meshes never loaded before, as a cell meets new objects
            shape = p.createCollisionShape(p.GEOM_MESH, fileName=str(path), physicsClientId=client)
            visual = p.createVisualShape(p.GEOM_MESH, fileName=str(path), physicsClientId=client)
            p.createMultiBody(0.1, shape, visual, physicsClientId=client)
        p.disconnect(client)
        sizes.append(resident_mb())
    print(sizes[-1] - sizes[2])  # MiB kept over rounds 4-6, after Bullet's pools have grown
""")


def _kept_mb(tmp_path, how: str) -> float:
    done = subprocess.run([sys.executable, "-c", ROUNDS, str(tmp_path), how], capture_output=True, text=True,
                          check=True)
    return float(done.stdout.split()[-1])


def test_a_client_frees_the_meshes_it_loaded_when_disconnected(tmp_path):
    kept = _kept_mb(tmp_path, "ours")
    cached = _kept_mb(tmp_path, "plain")  # PyBullet's default keeps every file it loaded
    assert kept < 1.5, f"{kept:.1f} MiB kept over 24 new meshes"  # measured 0.0-0.6
    assert cached > 3.0 + kept, f"a plain client kept only {cached:.1f} MiB"  # measured 4.9-5.1: the test can tell


def _python_kb_kept(make_obstacle, rounds: int = 40) -> float:
    """KiB of Python memory still held after `rounds` obstacles made and dropped (tracemalloc)."""
    import gc
    import tracemalloc

    make_obstacle(0)
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    for i in range(1, rounds + 1):
        make_obstacle(i)
    gc.collect()
    kept = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    return kept / 1024


def test_the_scenes_cloud_obstacles_keep_no_python_memory_and_are_the_clouds_hulls():
    import numpy as np

    from app.motion.scene import PlanningScene
    from hardware.bullet import p

    scene = PlanningScene()
    rng = np.random.default_rng(0)

    def cloud(i: int) -> np.ndarray:
        return np.random.default_rng(i).normal([0.5, 0.2, 0.08], [0.04, 0.04, 0.03], size=(2048, 3))

    def through_the_scene(i: int) -> None:
        scene.add_cloud("object", cloud(i), eye=np.array([0.5, -0.8, 0.9]))
        with scene.holding("object", np.eye(4)):
            pass
        scene.remove("object")

    def plain_vertices(i: int) -> None:  # PyBullet's own way in keeps the list it is given
        p.createCollisionShape(p.GEOM_MESH, vertices=cloud(i)[::8].tolist(), physicsClientId=scene.client)

    try:
        kept = _python_kb_kept(through_the_scene)
        leaked = _python_kb_kept(plain_vertices)
        assert kept < 40, f"{kept:.0f} KiB kept over 40 obstacles"
        assert leaked > 200 + kept, f"plain vertices kept only {leaked:.0f} KiB"  # the test can tell
        assert not any(scene._shape_dir.iterdir())  # each obstacle's hull file went with it

        points = cloud(99)
        scene.add_cloud("object", points)  # no eye: the hull of the points and their footprint
        probe = p.createMultiBody(0.0, p.createCollisionShape(p.GEOM_SPHERE, radius=0.002, physicsClientId=scene.client),
                                  physicsClientId=scene.client)
        for x in rng.uniform([0.35, 0.05, 0.0], [0.65, 0.35, 0.2], size=(60, 3)):
            p.resetBasePositionAndOrientation(probe, x.tolist(), [0, 0, 0, 1], physicsClientId=scene.client)
            touching = bool(p.getClosestPoints(probe, scene.obstacles["object"], 0.0, physicsClientId=scene.client))
            inside = _in_hull(x, np.concatenate([points, points * [1, 1, 0]]))
            distance = _hull_distance(x, np.concatenate([points, points * [1, 1, 0]]))
            if abs(distance) > 0.004:  # clear of the surface (probe radius plus Bullet's margins)
                assert touching == inside, (x, distance)
    finally:
        scene.close()
    assert not scene._shape_dir.exists()  # closing removes the scene's folder of hulls


def _hull_equations(points):
    from scipy.spatial import ConvexHull

    return ConvexHull(points).equations  # (F, 4): n . x + d <= 0 inside


def _in_hull(x, points) -> bool:
    return bool((_hull_equations(points) @ [*x, 1.0] <= 0).all())


def _hull_distance(x, points) -> float:
    """Signed distance bound to the hull's boundary: the largest plane distance (> 0 outside)."""
    return float((_hull_equations(points) @ [*x, 1.0]).max())
