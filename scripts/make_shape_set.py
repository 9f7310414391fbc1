"""Write the team's real-shape set: 21 meshes modelled after real products, as downloads come, and
the mug pybullet_data ships (a real mesh no one here made, used where it is installed).

Usage (repo root): .venv/bin/python scripts/make_shape_set.py [--out shapes/real]

Each shape is modelled from a product's typical published dimensions (the `product` line of
shapes/real/set.toml says which kind of product and its size); none comes from our generators'
families. They are written the way meshes arrive from the web - some in millimetres, some y-up,
some with a handle as a separate part sunk into the body (open-ended or closed), one with scan
debris - so that `nift objects import-set` exercises the repair too. The files are committed;
this script says how they were made and remakes them bit for bit.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from manifold3d import CrossSection, Manifold, Mesh
from shapely.geometry import Point

from app.objects.handle import handle_path
from app.objects.shaping import bumps, reshape_section
from app.objects.solids import closed_profile, hollow, revolve, to_trimesh, tube

MM = 0.001


@dataclass(frozen=True)
class Shape:
    name: str
    category: str
    product: str
    units: str = "m"  # the file's unit
    up: str = "z"  # the file's up axis
    fmt: str = "obj"


def mug(z, r, wall=0.004, bottom=0.007, handle=(0.55, 0.6, 0.034, 0.007, 2.5), squash=(1, 1, 1),
        rolled_rim=0.0, section=None, separate_handle=False):
    """A mug body of revolution (outer radius r(z)), a C handle (mid, span fractions, reach, tube
    radius, squareness), optionally a rolled rim and a non-round section; the handle returned apart when
    `separate_handle` (as a modelled download has it)."""
    z, r = np.asarray(z, float) * MM, np.asarray(r, float) * MM
    body, cavity = hollow(z, r, wall, bottom)
    H = z[-1]
    if rolled_rim:
        body = body + Manifold.revolve(
            CrossSection.circle(rolled_rim, 24).translate((r[-1], H - rolled_rim)), 96)
    if section:
        body = reshape_section(body, *section, z_full=H + 1, z_round=H + 2)
        cavity = reshape_section(cavity, *section, z_full=H + 1, z_round=H + 2)
    mid, span, reach, rh, square = handle
    zt, zb = H * (mid + span / 2), H * (mid - span / 2)
    rt, rb = np.interp([zt, zb], z, r) - wall / 2
    path = handle_path(rt, rb, zt, zb, reach, square)
    grip = tube(path, rh, squash=squash) - cavity
    if separate_handle:
        return to_trimesh(body), to_trimesh(grip)
    return to_trimesh(body + grip), None


def open_handle(z_top, z_bottom, reach, rh, x_wall):
    """An open-ended tube along a C arc whose ends sit 6 mm inside the wall (a modelled mug's handle)."""
    t = np.linspace(np.pi / 2, -np.pi / 2, 24)
    path = np.column_stack([x_wall - 0.006 + reach * np.cos(t), np.zeros_like(t),
                            (z_top + z_bottom) / 2 + (z_top - z_bottom) / 2 * np.sin(t)])
    return trimesh.creation.sweep_polygon(Point(0, 0).buffer(rh, 8), path, cap=False)


def bowl(z, r, wall=0.004, bottom=0.007, segments=96, foot=None):
    """A bowl of revolution (outer radius r(z), mm); `foot`: (height, radius) of a foot ring, mm."""
    z, r = np.asarray(z, float) * MM, np.asarray(r, float) * MM
    if foot:
        fh, fr = foot[0] * MM, foot[1] * MM
        z = np.concatenate([[0.0, fh], fh + 0.001 + z])
        r = np.concatenate([[fr, fr], r])
        bottom = max(bottom, fh + 0.004)
    body, _ = hollow(z, r, wall, bottom, segments=segments)
    return to_trimesh(body)


def bottle(z, r, cap, section=None, grip=None, pump=False):
    """A closed bottle of revolution (outer radius r(z), mm) with a cap (z0, height, bottom radius, top
    radius, mm) or a pump; a non-round body `section` (aspect, exponent, z_full, z_round mm); a grip
    handle (z_top, z_bottom, reach, radius, mm)."""
    z, r = np.asarray(z, float) * MM, np.asarray(r, float) * MM
    solid = revolve(closed_profile(z, r), 128)
    if section:
        aspect, exponent, z_full, z_round = section
        solid = reshape_section(solid, aspect, exponent, z_full * MM, z_round * MM)
    if grip:
        zt, zb, reach, rh = (v * MM for v in grip)
        xt, xb = np.interp([zt, zb], z, r) - 0.004
        solid = solid + tube(handle_path(xt, xb, zt, zb, reach, 3.0), rh)
    z0, h, rb, rt = (v * MM for v in cap)
    solid = solid + revolve(closed_profile(np.array([0.0, h - 0.002, h]) - 0.001,
                                           np.array([rb, rt, rt - 0.002]))).translate((0, 0, z0))
    if pump:
        stem = Manifold.cylinder(0.024, 0.005, 0.005, 32).translate((0, 0, z0 + h - 0.002))
        head = Manifold.cube((0.050, 0.020, 0.018)).translate((-0.012, -0.010, z0 + h + 0.020))
        solid = solid + stem + head
    return to_trimesh(solid)


def ribbed(z_lo, z_hi, radius, depth, ribs, n=60):
    """A body's profile with `ribs` round grooves `depth` deep between z_lo and z_hi (mm)."""
    z = np.linspace(z_lo, z_hi, n)
    return z, radius - depth * np.sin(np.pi * ribs * (z - z_lo) / (z_hi - z_lo)) ** 2


def shapes() -> list[tuple[Shape, trimesh.Trimesh]]:
    """Every shape of the set with its mesh (metres, z up, before it is written as its file says)."""
    out = []
    add = lambda shape, mesh: out.append((shape, mesh))  # noqa: E731
    zs = np.linspace(0, 95, 30)
    body, grip = mug(zs, 42 + 2 * zs / 95, wall=0.006, bottom=0.009, handle=(0.5, 0.62, 0.036, 0.008, 3.0),
                     separate_handle=True)
    add(Shape("diner-mug", "mug", "diner mug, 85-88 mm wide, 95 mm tall, 6 mm walls, D handle (closed part sunk "
              "into the body, as modelled)", "mm", "y"), trimesh.util.concatenate([body, grip]))
    add(Shape("espresso-cup", "mug", "espresso cup, 62 mm wide, 58 mm tall, ring handle with a 21 mm hole"),
        mug(np.linspace(0, 58, 20), np.linspace(29, 31, 20), bottom=0.006,
            handle=(0.52, 0.55, 0.021 + 0.005 + 0.002, 0.005, 2.0))[0])
    zs = np.linspace(0, 120, 40)
    add(Shape("latte-mug", "mug", "latte mug, 70 mm base flaring to 92 mm, 120 mm tall"),
        mug(zs, 35 + 11 * (zs / 120) ** 1.5, handle=(0.5, 0.55, 0.036, 0.007, 3.5))[0])
    add(Shape("camp-mug", "mug", "enamel camping mug, 80 mm wide, 80 mm tall, rolled rim, flat strap handle",
              "mm"), mug(np.linspace(0, 80, 20), np.full(20, 40.0), wall=0.003, bottom=0.005,
                         handle=(0.55, 0.62, 0.034, 0.007, 4.0), squash=(0.6, 2.2, 0.6), rolled_rim=0.003)[0])
    zs = np.linspace(0, 100, 40)
    add(Shape("barrel-mug", "mug", "barrel mug, 76 mm base, 92 mm belly, 100 mm tall", up="y"),
        mug(zs, 38 + 8 * np.sin(np.pi * zs / 100) + 2 * zs / 100, wall=0.005)[0])
    add(Shape("square-mug", "mug", "square mug, 80 x 80 mm rounded-square section, 95 mm tall"),
        mug(np.linspace(0, 95, 30), np.full(30, 40.0), section=(1.0, 4.0))[0])
    zt, zb = 0.092 * 0.8, 0.092 * 0.2
    body = to_trimesh(hollow(np.linspace(0, 0.092, 30), np.full(30, 0.041), 0.004, 0.007)[0])
    add(Shape("tea-mug", "mug", "tea mug, 82 mm wide, 92 mm tall; its handle an open-ended tube sunk into the "
              "body (a modelled download)", "mm", fmt="stl"),
        trimesh.util.concatenate([body, open_handle(zt, zb, 0.034, 0.007, 0.041)]))

    zs = np.linspace(0, 57, 30)
    add(Shape("cereal-bowl", "bowl", "cereal bowl, 150 mm wide, 65 mm tall on an 8 mm foot ring"),
        bowl(zs, 42 + 33 * (1 - (1 - zs / 57) ** 2), foot=(8, 40)))
    zs = np.linspace(0, 52, 30)
    add(Shape("rice-bowl", "bowl", "rice bowl, 118 mm wide, 62 mm tall on a 10 mm foot", "mm"),
        bowl(zs, 30 + 29 * (1 - (1 - zs / 52) ** 1.6), foot=(10, 28)))
    zs = np.linspace(0, 55, 30)
    add(Shape("soup-bowl", "bowl", "wide soup bowl, 165 mm wide, 55 mm tall, rim flared out"),
        bowl(zs, 40 + 34 * (1 - (1 - zs / 55) ** 2.2) + 8.5 * np.clip((zs - 42) / 13, 0, 1) ** 2))
    zs = np.linspace(0, 82, 40)
    add(Shape("ramen-bowl", "bowl", "ramen bowl, 168 mm wide, 82 mm tall, deep", up="y", fmt="ply"),
        bowl(zs, 38 + 46 * (1 - (1 - zs / 82) ** 1.8), wall=0.005))
    zs = np.linspace(0, 60, 30)
    add(Shape("octagon-bowl", "bowl", "faceted bowl, eight sides, 140 mm across the corners, 60 mm tall"),
        bowl(zs, 38 + 32 * (1 - (1 - zs / 60) ** 2), segments=8))
    zs = np.linspace(0, 58, 30)
    scan = bowl(zs, 40 + 30 * (1 - (1 - zs / 58) ** 2), foot=(6, 36))
    scan = to_trimesh(bumps(Manifold(Mesh(
        vert_properties=np.asarray(scan.vertices, np.float32), tri_verts=np.asarray(scan.faces, np.uint32))),
        0.0006, np.random.default_rng(5)))
    debris = trimesh.Trimesh([[0.09, 0, 0.01], [0.091, 0, 0.01], [0.0905, 0.00001, 0.03]], [[0, 1, 2]])
    add(Shape("scanned-bowl", "bowl", "scanned bowl, 140 mm wide, 64 mm tall, surface lumps and a sliver "
              "of scan debris", fmt="ply"), trimesh.util.concatenate([scan, debris]))

    z, r = ribbed(0, 150, 32.5, 1.5, 6)
    add(Shape("water-500ml", "bottle", "500 ml water bottle, 65 mm wide, 205 mm tall, ribbed, 28 mm PCO neck "
              "and screw cap", "mm"),
        bottle(np.concatenate([z, [170, 180, 187]]), np.concatenate([r, [20, 14.5, 14.5]]), (186, 18, 15.2, 15.2)))
    add(Shape("beer-bottle", "bottle", "330 ml beer bottle, 60 mm wide, 230 mm tall, long neck, crown cap"),
        bottle([0, 140, 165, 185, 218], [30, 30, 20, 13.5, 13.0], (217, 12, 14.5, 14.5)))
    add(Shape("shampoo-oval", "bottle", "shampoo, 96 x 58 mm oval body, 190 mm tall, flip-top cap tapering "
              "18 deg, no lip", up="y"),
        bottle([0, 150, 160, 168, 172], [48, 48, 36, 15, 15], (171, 20, 20, 20 - 20 * np.tan(np.radians(18))),
               section=(0.60, 2.0, 150, 168)))
    add(Shape("dish-soap", "bottle", "dish soap, 75 x 45 mm rounded-rectangle body, 220 mm tall, push-pull "
              "conical cap tapering 25 deg", "mm"),
        bottle([0, 170, 185, 193, 198], [37.5, 37.5, 22, 13, 13], (197, 23, 14, 14 - 23 * np.tan(np.radians(25))),
               section=(0.60, 4.5, 170, 193)))
    add(Shape("soap-pump", "bottle", "liquid soap with a 28/410 pump, 70 mm wide, 215 mm tall"),
        bottle([0, 130, 145, 152, 158], [35, 35, 22, 14, 14], (157, 14, 17, 17), pump=True))
    add(Shape("detergent-jug", "bottle", "750 ml detergent jug, 100 x 70 mm, 200 mm tall, grip handle, "
              "45 mm cap", up="y", fmt="stl"),
        bottle([0, 140, 165, 172, 176], [48, 48, 30, 22, 22], (175, 24, 23.5, 23.5), section=(0.72, 3.0, 140, 172),
               grip=(158, 80, 30, 10)))
    z = np.linspace(0, 170, 40)
    add(Shape("sports-bottle", "bottle", "sports drink bottle, 72 mm wide, waisted to 62 mm, 220 mm tall, "
              "32 mm cap"),
        bottle(np.concatenate([z, [185, 193, 197]]), np.concatenate([36 - 5 * np.sin(np.pi * z / 170) ** 2,
                                                                     [22, 15, 15]]), (196, 24, 16.5, 16.5)))
    add(Shape("sauce-bottle", "bottle", "squeeze sauce bottle, 70 x 45 mm flat body, 180 mm tall, conical "
              "flip cap tapering 22 deg", "mm", "y", "ply"),
        bottle([0, 135, 150, 155, 158], [35, 35, 20, 16, 16], (157, 22, 18, 18 - 22 * np.tan(np.radians(22))),
               section=(0.64, 3.0, 135, 155)))
    return out


UP = {"z": np.eye(4), "y": trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0])}  # z-up -> y-up


def write(out: Path) -> None:
    """Write every shape's file and set.toml (the names, categories, units, up axes and products)."""
    out.mkdir(parents=True, exist_ok=True)
    lines = ['# The team\'s real-shape set: meshes modelled after real products (scripts/make_shape_set.py).',
             '# nift objects import-set shapes/real/set.toml; nift bench-jobs --objects shapes/real/set.toml', '']
    for shape, mesh in shapes():
        m = mesh.copy()
        m.apply_transform(UP[shape.up])
        m.apply_scale({"m": 1.0, "mm": 1000.0}[shape.units])
        file = f"{shape.name}.{shape.fmt}"
        m.export(out / file)
        lines += ["[[object]]", f'name = "{shape.name}"', f'category = "{shape.category}"', f'file = "{file}"',
                  f'units = "{shape.units}"', f'up = "{shape.up}"', f'product = "{shape.product}"', ""]
    lines += ["[[object]]", 'name = "pybullet-mug"', 'category = "mug"', 'file = "objects/mug.obj"',
              'package = "pybullet_data"', 'product = "the mug PyBullet ships (pybullet_data, zlib licence): a body '
              'and an open handle part, as downloaded"', ""]
    (out / "set.toml").write_text("\n".join(lines))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("shapes/real"))
    write(parser.parse_args().out)


if __name__ == "__main__":
    main()
