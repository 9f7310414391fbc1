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
