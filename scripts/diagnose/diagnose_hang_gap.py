"""Room around the peg for test mugs hung at the teacher's hang: the mesh's, and Bullet's at a margin.

    .venv/bin/python scripts/diagnose/diagnose_hang_gap.py [--margin M] [--scale S] [INSTANCE ...]

Prints, per mug, the gap on its mesh and in the simulated cell (mm); --margin sets the cell's
`mesh_margin` (Bullet's own default is 0.001).
"""
from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from app.objects import generate, rack, semantics, split
from app.simcell.cell import CellConfig, SimCell
from app.simcell.hang_gap import bullet_gap, mesh_gap
from app.simcell.spawn import spawn
from app.tasks.teacher import hang_pose


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("instances", nargs="*", type=int)
    ap.add_argument("--margin", type=float, default=CellConfig().world.mesh_margin)
    ap.add_argument("--scale", type=float, default=1.0)
    args = ap.parse_args()
    instances = args.instances or split("mug", "test")[:10]
    config = CellConfig()
    config = replace(config, world=replace(config.world, mesh_margin=args.margin))
    with SimCell(config) as cell:
        T_base_rack = cell.world.pose(cell.fixtures["rack"])
        rows = []
        for instance in instances:
            T_rack_obj = hang_pose(semantics(generate("mug", instance)), rack(), args.scale)
            obj = spawn(cell.world, "mug", instance, "arbitrary", scale=args.scale, T_world_obj=T_base_rack @ T_rack_obj)
            rows.append((mesh_gap(obj.mesh, T_rack_obj), bullet_gap(cell.world.require(), obj.body, cell.fixtures["rack"])))
            cell.world.remove(obj.body)
            print(f"mug {instance} scale {args.scale}: mesh {1000 * rows[-1][0]:.1f} mm, bullet {1000 * rows[-1][1]:.1f} mm",
                  flush=True)
    gaps = np.array(rows) * 1000
    print(f"margin {args.margin} m: median gap mesh {np.median(gaps[:, 0]):.1f} mm, bullet {np.median(gaps[:, 1]):.1f} mm, "
          f"bullet below 0.5 mm on {int((gaps[:, 1] < 0.5).sum())} of {len(gaps)}")


if __name__ == "__main__":
    main()
