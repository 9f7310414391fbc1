"""The import's repair of broken downloads: each broken mesh comes out one watertight solid whose
volume is within 5 % of the solid it was meant to be, or it is refused in one line."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from app.objects.loading import prepare_mesh, repair
from app.objects.mesh_repair import NotASolid, boundary_loops, capped, manifold_pieces
from tests.broken_meshes import BROKEN, body, handle, nonmanifold_fan, open_sheet


@pytest.mark.parametrize("case", list(BROKEN))
def test_each_broken_mesh_is_repaired_to_its_intended_solid(case):
    broken, intended = BROKEN[case]()
    assert not (broken.is_watertight and broken.is_winding_consistent and broken.body_count == 1), "not broken"
    fixed, notes = repair(broken, case)
    assert fixed.is_watertight and fixed.is_winding_consistent and fixed.body_count == 1
    assert fixed.volume > 0 and np.isclose(fixed.volume, intended.volume, rtol=0.05), (fixed.volume, intended.volume)
    assert notes, "the repair says what it did"


def test_the_repair_says_what_it_dropped_and_how_it_closed():
    _, notes = repair(BROKEN["slivers beside a closed body"]()[0])
    assert any("dropped" in n and "faces" in n for n in notes)
    _, notes = repair(BROKEN["an open-ended handle tube sunk into a body"]()[0])
    assert any("open ends capped" in n for n in notes) and any("union" in n for n in notes)


def test_a_sheet_is_refused_in_one_line():
    with pytest.raises(NotASolid, match="cannot be a solid object") as err:
        repair(open_sheet(), "sheet")
    assert "\n" not in str(err.value)


def test_a_fan_splits_off_at_its_non_manifold_edge():
    broken, _ = nonmanifold_fan()
    pieces = manifold_pieces(broken)
    assert len(pieces[0].faces) == len(body().faces) and sum(len(p.faces) for p in pieces) == len(broken.faces)


def test_capping_closes_a_tube_into_the_swept_solid():
    tube = handle(cap=False)
    assert len(boundary_loops(tube)) == 2
    closed = capped(tube)
    trimesh.repair.fix_normals(closed)
    assert closed.is_watertight and np.isclose(closed.volume, handle(cap=True).volume, rtol=0.02)


def test_a_repaired_mug_is_put_upright_in_metres():
    broken, intended = BROKEN["an open-ended handle tube sunk into a body"]()
    broken.apply_scale(1000.0)  # a file in millimetres
    prepared = prepare_mesh(broken, name="mug.stl")
    assert prepared.units == "mm" and np.isclose(prepared.mesh.volume, intended.volume, rtol=0.05)
    assert np.isclose(prepared.mesh.bounds[0, 2], 0.0, atol=1e-9)
