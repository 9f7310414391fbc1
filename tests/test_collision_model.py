"""CoACD's convex decomposition, run in its child process: convex parts that fill a concave solid."""
import numpy as np
import pytest
import trimesh
from shapely.geometry import Polygon

from app.objects.collision import decompose, read_parts_obj, write_parts_obj


def _l_shape() -> trimesh.Trimesh:
    """A watertight L-shaped prism (3 cm thick): concave, so no single convex part can be it."""
    outline = Polygon([(0, 0), (0.1, 0), (0.1, 0.03), (0.03, 0.03), (0.03, 0.1), (0, 0.1)])
    return trimesh.creation.extrude_polygon(outline, 0.03)


def test_a_concave_solid_comes_back_as_convex_parts_that_fill_it():
    mesh = _l_shape()
    parts = decompose(mesh)
    assert len(parts) >= 2 and all(part.is_convex for part in parts)
    assert sum(part.volume for part in parts) == pytest.approx(mesh.volume, rel=0.02)  # 1.53e-4 m^3
    inside = trimesh.sample.volume_mesh(mesh, 4000)  # points inside the L (rejection sampling)
    covered = np.any([part.contains(inside) for part in parts], axis=0)
    assert len(inside) > 500 and covered.mean() > 0.97


def test_the_parts_round_trip_through_their_obj(tmp_path):
    parts = [trimesh.creation.box([0.01, 0.02, 0.03]), trimesh.creation.icosphere(radius=0.02)]
    back = read_parts_obj(write_parts_obj(parts, tmp_path / "parts.obj"))
    assert len(back) == 2
    for a, b in zip(parts, back):
        np.testing.assert_allclose(b.vertices, a.vertices, atol=1e-7)
        np.testing.assert_array_equal(b.faces, a.faces)


def test_a_mesh_with_holes_is_refused():
    open_box = trimesh.creation.box([0.05, 0.05, 0.05])
    open_box.update_faces(np.arange(len(open_box.faces)) > 1)  # two triangles gone
    with pytest.raises(ValueError, match="watertight"):
        decompose(open_box)
