"""The rack of the cell in a physics world and the place judge on it, for the mug diagnosis scripts
(`diagnose_mug_place.py`, `diagnose_peg_centering.py`): does a test mug hang at a pose?"""
import numpy as np

from app.simcell.cell import CellConfig, add_fixtures
from app.simcell.judges import judge_place
from app.simcell.spawn import spawn
from hardware.sim.world import SimWorld, SimWorldConfig


class RackJudge:
    """A world with the cell's fixtures; `hangs` spawns a mug, sets it at a pose on the rack and judges."""

    def __init__(self, cell: CellConfig = CellConfig()) -> None:
        self.world = SimWorld(SimWorldConfig())
        self.world.connect()
        self.rack_body = add_fixtures(self.world, cell)["rack"]
        self.T_base_rack = cell.fixture_pose("rack")

    def verdict(self, seed: int, scale: float, T_base_obj: np.ndarray, T_rack_obj: np.ndarray):
        """The place judge's verdict for test mug `seed` (spawned at T_base_obj) set at T_rack_obj."""
        obj = spawn(self.world, "mug", seed, "upright", scale=scale, T_world_obj=T_base_obj)
        try:
            return judge_place(self.world, obj, self.T_base_rack @ T_rack_obj, self.rack_body, upright=False)
        finally:
            self.world.remove(obj.body)

    def hangs(self, seed: int, scale: float, T_base_obj: np.ndarray, T_rack_obj: np.ndarray) -> bool:
        """Whether the mug hangs there."""
        return self.verdict(seed, scale, T_base_obj, T_rack_obj).success
