"""Regenerates the tiny test assets in this folder (run from the repo root).

A 2 cm cube (centred at the origin, outward winding) in every format the loader supports, with a
material and, for OBJ, a 4x4 texture; plus deliberately bad files for the error tests.
"""

from pathlib import Path

import numpy as np
import trimesh
from PIL import Image

HERE = Path(__file__).parent
H = 0.01  # half edge, metres


def cube() -> trimesh.Trimesh:
    return trimesh.creation.box(extents=(2 * H, 2 * H, 2 * H))


def write_obj_with_texture() -> None:
    # One quad per face with its own 4 vertices so every face carries full-square uvs.
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    lines = ["mtllib cube.mtl", "o cube"]
    faces = []
    vid = 1
    for axis in range(3):
        for sign in (-1.0, 1.0):
            for a, b in corners:
                p = np.zeros(3)
                p[axis] = sign * H
                u_ax, v_ax = [k for k in range(3) if k != axis]
                p[u_ax], p[v_ax] = a * H, b * H
                lines.append(f"v {p[0]:.6f} {p[1]:.6f} {p[2]:.6f}")
            # outward winding: the (u, v) corner order is CCW around +axis when the cyclic axis
            # order is kept; flip for the negative side.
            idx = [vid, vid + 1, vid + 2, vid + 3]
            if (sign > 0) != ((u_ax, v_ax) in ((0, 1), (1, 2), (2, 0))):
                idx.reverse()
            faces.append(idx)
            vid += 4
    for a, b in corners:
        lines.append(f"vt {(a + 1) / 2:.1f} {(b + 1) / 2:.1f}")
    lines.append("usemtl painted")
    for f in faces:
        uv = [((i - 1) % 4) + 1 for i in f]
        lines.append(f"f {f[0]}/{uv[0]} {f[1]}/{uv[1]} {f[2]}/{uv[2]}")
        lines.append(f"f {f[0]}/{uv[0]} {f[2]}/{uv[2]} {f[3]}/{uv[3]}")
    (HERE / "cube.obj").write_text("\n".join(lines) + "\n")
    (HERE / "cube.mtl").write_text(
        "newmtl painted\nKd 0.8 0.2 0.1\nKs 0.5 0.5 0.5\nNs 40\nd 0.5\nmap_Kd cube_texture.png\n"
    )
    img = np.zeros((4, 4, 3), np.uint8)
    img[::2, ::2] = (255, 0, 0)
    img[1::2, 1::2] = (0, 0, 255)
    Image.fromarray(img).save(HERE / "cube_texture.png")


def write_dae(m: trimesh.Trimesh) -> None:
    """A minimal COLLADA 1.4 file with one node scaled by 2 (tests node transforms)."""
    pos = " ".join(f"{x:.6f}" for x in (m.vertices / 2).ravel())
    idx = " ".join(str(i) for i in m.faces.ravel())
    (HERE / "cube.dae").write_text(f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_effects><effect id="fx"><profile_COMMON><technique sid="c"><phong>
    <diffuse><color>0.1 0.3 0.9 1</color></diffuse>
  </phong></technique></profile_COMMON></effect></library_effects>
  <library_materials><material id="mat" name="blue"><instance_effect url="#fx"/></material>
  </library_materials>
  <library_geometries><geometry id="g" name="cube"><mesh>
    <source id="p"><float_array id="pa" count="{m.vertices.size}">{pos}</float_array>
      <technique_common><accessor source="#pa" count="{len(m.vertices)}" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles material="m0" count="{len(m.faces)}">
      <input semantic="VERTEX" source="#v" offset="0"/>
      <p>{idx}</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n">
    <scale>2 2 2</scale>
    <instance_geometry url="#g"><bind_material><technique_common>
      <instance_material symbol="m0" target="#mat"/></technique_common></bind_material>
    </instance_geometry></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
""")


def main() -> None:
    write_obj_with_texture()
    m = cube()
    m.export(HERE / "cube.stl", file_type="stl_ascii")
    m.export(HERE / "cube.ply", file_type="ply", encoding="ascii")
    m.visual = trimesh.visual.TextureVisuals(
        material=trimesh.visual.material.PBRMaterial(baseColorFactor=[30, 200, 60, 255])
    )
    m.export(HERE / "cube.glb")
    write_dae(cube())
    # Bad inputs.
    (HERE / "not_a_mesh.obj").write_text("this is a text file, not a mesh\n" * 20)
    (HERE / "empty.stl").write_text("solid empty\nendsolid empty\n")
    (HERE / "nan_vertex.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    )
    (HERE / "zero_area.obj").write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 0 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 1 2 5\n"
    )


if __name__ == "__main__":
    main()
