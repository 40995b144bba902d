"""The path-tracing benchmark scene and its export to the peers (Blender Cycles, Mitsuba 3).

One scene, described once as plain data (:class:`SceneDesc`): 20 built-in objects dropped into
the tote by :func:`mgn.scene.drop_scene`, their PBR materials (``mgn.render.path.PbrMaterial``),
two rectangular area lights and a uniform environment, seen by one camera of the MetaGraspNet rig.
Every engine gets the same triangles at the same world poses, the same materials mapped as closely
as it supports, the same lights in the same radiometric units, and the same pinhole camera
(intrinsics incl. the principal point; OpenCV camera frame converted to each engine's frame).

Radiometry: an area light of ``intensity`` I and ``color`` c emits radiance I * c from its +z
side; the environment has radiance ``color * intensity``. Cycles gets the lights as one-sided
emissive meshes (Emission shader strength = radiance, so no watt conversion is involved) and the
environment as the world Background; Mitsuba gets ``rectangle`` shapes with ``area`` emitters and
a ``constant`` emitter.

Alignment is checked by :func:`cycles_ids` / :func:`mitsuba_ids`: each object emits its instance
id and nothing else, one sample through each pixel centre, compared with mgn's instance ids.
"""

from __future__ import annotations

import dataclasses
import io
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

N_OBJECTS = 20
DROP_SEED = 7
RIG_SEED = 2024
VIEW = 0
#: A varied set of built-in objects: printed boxes, metal cans, plastics, glass, black items.
OBJECT_NAMES = (
    "box_cereal",
    "box_tea",
    "box_medicine",
    "can_soda",
    "can_food",
    "spray_can",
    "bottle_water",
    "bottle_detergent",
    "jar",
    "mug",
    "bowl",
    "cup_black",
    "pipe_elbow",
    "l_bracket",
    "hex_nut",
    "pear",
    "tennis_ball",
    "wine_glass",
    "bottle_clear",
    "remote_control",
)
MAX_BOUNCES = 6  # path segments after the camera ray, as mgn's PathTraceOptions.max_bounces


@dataclasses.dataclass(frozen=True)
class Pbr:
    """glTF metallic-roughness material (the fields of mgn.render.path.PbrMaterial)."""

    base_color: tuple[float, float, float]
    metallic: float
    roughness: float
    ior: float
    transmission: float
    emission: tuple[float, float, float]
    texture: np.ndarray | None  # (H, W, 3) uint8 sRGB, multiplies base_color


@dataclasses.dataclass(frozen=True)
class Part:
    """Triangles of one instance that share one material, in the object frame."""

    vertices: np.ndarray  # (V, 3) float64, m
    faces: np.ndarray  # (F, 3) int32
    uvs: np.ndarray | None  # (V, 2) float32
    material: Pbr
    normals: np.ndarray | None = None  # (F, 3, 3) unit shading normal per face corner


@dataclasses.dataclass(frozen=True)
class Item:
    name: str
    instance_id: int  # 0 = the tote
    X_WO: np.ndarray  # (4, 4)
    parts: tuple[Part, ...]


@dataclasses.dataclass(frozen=True)
class Light:
    X_WL: np.ndarray  # emits towards +z_L
    size: tuple[float, float]  # full side lengths along x_L, y_L, m
    radiance: tuple[float, float, float]


@dataclasses.dataclass(frozen=True)
class Camera:
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    X_WC: np.ndarray  # OpenCV frame: x right, y down, z forward


@dataclasses.dataclass(frozen=True)
class SceneDesc:
    items: tuple[Item, ...]
    lights: tuple[Light, ...]
    environment: tuple[float, float, float]  # uniform radiance
    camera: Camera
    max_bounces: int = MAX_BOUNCES


# ----------------------------------------------------------------------------------------------
# The scene (mgn side)


def cameras() -> Any:
    """The module with Intrinsics, CameraView and mgn_rig (mgn.scene.cameras; older layout:
    mgn.render)."""
    try:
        from mgn.scene import cameras as mod
    except ImportError:
        from mgn import render as mod
    return mod


def tote_mesh_of(spec: Any) -> Any:
    """The tote mesh with its material (mgn.objects.tote_mesh; older layout: mgn.render.views)."""
    try:
        from mgn.objects import tote_mesh
    except ImportError:
        from mgn.render.views import tote_mesh
    return tote_mesh(spec)


def drop(path: Path, names: tuple[str, ...] = OBJECT_NAMES, seed: int = DROP_SEED) -> Path:
    """Drop the benchmark objects (fixed seed) and write the scene JSON to ``path``."""
    from mgn.scene import compose_objects, drop_scene

    objects = compose_objects(names=list(names))
    scene = drop_scene(objects, seed=seed)
    from mgn.io.scene_json import write_scene_json

    return write_scene_json(scene, path)


def pbr_materials(mesh: Any) -> list[Any]:
    """mgn's PBR materials of a mesh, one per material slot, as mgn's ``path`` engine uses them
    (``mgn.render.materials.pbr_material``: the built-in objects' own PBR parameters), else
    ``PbrMaterial.from_material`` of the legacy material."""
    slots = list(mesh.materials) or [None]
    try:
        from mgn.render import path as mpath
    except ImportError:  # the tracer is not built: the legacy material, mapped here
        return [_fallback_pbr(m) for m in slots]
    try:
        from mgn.render.materials import pbr_material  # the built-in objects' own PBR parameters
    except ImportError:
        pbr_material = mpath.PbrMaterial.from_material
    return [mpath.PbrMaterial() if m is None else pbr_material(m) for m in slots]


def _fallback_pbr(m: Any) -> Pbr:
    if m is None:
        return Pbr((0.8, 0.8, 0.8), 0.0, 0.5, 1.5, 0.0, (0.0, 0.0, 0.0), None)
    tex = None
    if m.texture_data:
        from PIL import Image

        tex = np.asarray(Image.open(io.BytesIO(m.texture_data)).convert("RGB"), np.uint8)
    rough = math.sqrt(2.0 / (float(m.shininess) + 2.0)) ** 0.5
    base = tuple(float(x) for x in np.asarray(m.base_color)[:3])
    return Pbr(base, 0.0, rough, 1.5, 1.0 - float(m.opacity), (0.0, 0.0, 0.0), tex)


def _texture_of(pm: Any) -> np.ndarray | None:
    tex = getattr(pm, "base_color_texture", getattr(pm, "texture", None))
    return None if tex is None else np.asarray(tex, np.uint8)[..., :3]


def _to_pbr(pm: Any) -> Pbr:
    return Pbr(
        tuple(float(x) for x in pm.base_color),
        float(pm.metallic),
        float(pm.roughness),
        float(pm.ior),
        float(pm.transmission),
        tuple(float(x) for x in pm.emission),
        _texture_of(pm),
    )


#: (position, size, intensity) of the two white rectangular area lights, aimed at the tote
#: centre; and the uniform environment radiance.
LIGHTS = (((0.45, -0.35, 1.25), (0.5, 0.5), 12.0), ((-0.55, 0.25, 1.1), (0.3, 0.6), 6.0))
ENVIRONMENT = 0.35


def lights_and_environment() -> tuple[list[Light], tuple[float, float, float]]:
    """The benchmark lighting as plain data (mgn_lighting() gives mgn's objects)."""
    lights = [
        Light(look_at_light(np.asarray(p, float), np.zeros(3)), s, (i, i, i)) for p, s, i in LIGHTS
    ]
    return lights, (ENVIRONMENT,) * 3


def mgn_lighting() -> tuple[list[Any], Any]:
    """mgn's AreaLight list and Environment of the benchmark lighting."""
    from mgn.render import path as mpath

    lights = [
        mpath.AreaLight(
            X_WL=look_at_light(np.asarray(p, float), np.zeros(3)),
            shape="rect",
            size=s,
            intensity=i,
        )
        for p, s, i in LIGHTS
    ]
    env = mpath.Environment(kind="uniform", color=(1.0, 1.0, 1.0), intensity=ENVIRONMENT)
    return lights, env


def look_at_light(position: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Pose of a light at ``position`` whose +z axis points at ``target``."""
    z = target - position
    z = z / np.linalg.norm(z)
    up = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    X = np.eye(4)
    X[:3, 0], X[:3, 1], X[:3, 2], X[:3, 3] = x, y, z, position
    return X


def camera(width: int, view: int = VIEW) -> tuple[Any, np.ndarray]:
    """mgn Intrinsics (MetaGraspNet synthetic camera scaled to ``width``) and X_WC of ``view``."""
    cams = cameras()
    Intrinsics, mgn_rig = cams.Intrinsics, cams.mgn_rig

    K = Intrinsics.mgn_synthetic().scaled(width / 1200)
    poses, _ = mgn_rig(RIG_SEED, (0.0, 0.0, 0.0))
    return K, np.asarray(poses[view], np.float64)


def mgn_inputs(scene_json: Path) -> dict[str, Any]:
    """Everything mgn's PathScene takes: meshes, poses, ids, materials, lights, environment."""

    from mgn.io.scene_json import read_scene_json

    scene = read_scene_json(scene_json)
    meshes, poses, ids, materials, names = [], [], [], [], []
    for mesh, X, inst in scene.render_items():
        meshes.append(mesh)
        poses.append(np.asarray(X, np.float64))
        ids.append(int(inst))
        materials.append(pbr_materials(mesh))
        names.append(mesh.name)
    tote = tote_mesh_of(scene.tote)
    meshes.append(tote)
    poses.append(np.eye(4))
    ids.append(0)
    materials.append(pbr_materials(tote))
    names.append("tote")
    return {
        "meshes": meshes,
        "poses": np.stack(poses),
        "instance_ids": ids,
        "materials": materials,
        "names": names,
    }


def describe(
    scene_json: Path, width: int, view: int = VIEW, cx_shift: float = 0.0, cy_shift: float = 0.0
) -> SceneDesc:
    """The scene as plain data for the peers (same triangles, materials, lights, camera).

    ``cx_shift``, ``cy_shift`` move the principal point (px) to check that each peer honours it."""
    inp = mgn_inputs(scene_json)
    items = []
    for mesh, X, inst, mats, name in zip(
        inp["meshes"],
        inp["poses"],
        inp["instance_ids"],
        inp["materials"],
        inp["names"],
        strict=True,
    ):
        V = np.asarray(mesh.vertices, np.float64)
        F = np.asarray(mesh.faces, np.int32)
        uv = None if mesh.uvs is None else np.asarray(mesh.uvs, np.float32)
        fm = np.asarray(mesh.face_materials, np.int64)
        if fm.size != len(F):
            fm = np.zeros(len(F), np.int64)
        normals = corner_normals(V, F)
        parts = []
        for slot, pm in enumerate(mats):
            sel = fm == slot
            if np.any(sel):
                parts.append(Part(V, F[sel], uv, _to_pbr(pm), normals[sel]))
        items.append(Item(name, inst, X, tuple(parts)))
    lights, env = lights_and_environment()
    K, X_WC = camera(width, view)
    cam = Camera(K.width, K.height, K.fx, K.fy, K.cx + cx_shift, K.cy + cy_shift, X_WC)
    return SceneDesc(tuple(items), tuple(lights), env, cam)


def crop(desc: SceneDesc, x0: int, y0: int, width: int, height: int) -> SceneDesc:
    """The same scene seen through a window of its camera: pixels [x0, x0 + width) x
    [y0, y0 + height) of the full image, as a camera with the same focal lengths, the principal
    point moved by (-x0, -y0) and the window's size (pixel (u, v) of the crop is pixel
    (x0 + u, y0 + v) of the full image, the same rays)."""
    c = desc.camera
    if not (0 <= x0 and 0 <= y0 and 0 < width and 0 < height):
        raise ValueError(f"crop window ({x0}, {y0}, {width}, {height}) must be non-negative")
    if x0 + width > c.width or y0 + height > c.height:
        raise ValueError(
            f"crop window ({x0}, {y0}, {width}, {height}) must lie inside the "
            f"{c.width}x{c.height} image"
        )
    cam = dataclasses.replace(c, width=width, height=height, cx=c.cx - x0, cy=c.cy - y0)
    return dataclasses.replace(desc, camera=cam)


CREASE_COS = math.cos(math.radians(45.0))


def corner_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(F, 3, 3) shading normals as mgn's path tracer makes them: at each face corner, the
    angle-weighted mean of the normals of the faces around the position-welded vertex that lie
    within 45 degrees of this face's normal (sharp edges stay sharp)."""
    P = V[F]  # (F, 3, 3)
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    ang = np.empty((len(F), 3))
    for k in range(3):
        a = P[:, (k + 1) % 3] - P[:, k]
        b = P[:, (k + 2) % 3] - P[:, k]
        a /= np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-30)
        b /= np.maximum(np.linalg.norm(b, axis=1, keepdims=True), 1e-30)
        ang[:, k] = np.arccos(np.clip(np.sum(a * b, axis=1), -1.0, 1.0))
    _, weld = np.unique(V.astype(np.float32), axis=0, return_inverse=True)
    wc = weld.reshape(-1)[F.reshape(-1)]  # welded vertex of each corner
    order = np.argsort(wc, kind="stable")
    ws = wc[order]
    bounds = np.flatnonzero(np.diff(ws)) + 1
    starts = np.concatenate([[0], bounds])
    sizes = np.diff(np.concatenate([starts, [len(ws)]]))
    grp_start = np.repeat(starts, sizes)
    grp_size = np.repeat(sizes, sizes)
    total = int(grp_size.sum())
    i = np.repeat(np.arange(len(ws)), grp_size)
    j = np.repeat(grp_start, grp_size) + (
        np.arange(total) - np.repeat(np.cumsum(grp_size) - grp_size, grp_size)
    )
    ci, cj = order[i], order[j]  # corner ids (3 f + k)
    fi, fj = ci // 3, cj // 3
    keep = np.sum(n[fi] * n[fj], axis=1) >= CREASE_COS
    w = (n[fj] * ang.reshape(-1)[cj][:, None])[keep]
    acc = np.zeros((3 * len(F), 3))
    for d in range(3):
        acc[:, d] = np.bincount(ci[keep], weights=w[:, d], minlength=3 * len(F))
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    fallback = np.repeat(n, 3, axis=0)
    out = np.where(length > 0, acc / np.maximum(length, 1e-30), fallback)
    return out.reshape(len(F), 3, 3)


def srgb_to_linear(u8: np.ndarray) -> np.ndarray:
    c = np.asarray(u8, np.float32) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4).astype(np.float32)


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def _png_bytes(rgb: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.asarray(rgb, np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


# ----------------------------------------------------------------------------------------------
# Blender Cycles (bpy)

CV_TO_BLENDER = np.diag([1.0, -1.0, -1.0, 1.0])  # OpenCV camera -> Blender camera (-z forward)


def cycles_scene(desc: SceneDesc, tmp: Path, threads: int) -> Any:
    """Builds the scene in a fresh Blender session (CPU Cycles). Returns bpy.context.scene."""
    import bpy
    from mathutils import Matrix

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    scene.render.use_persistent_data = True  # BVH built once per scene, as mgn's PathScene
    c = scene.cycles
    c.use_adaptive_sampling = False
    c.use_denoising = False
    # Cycles samples the lights at the vertex where a path reaches its bounce limit, mgn does not:
    # Cycles' N bounces are mgn's N + 1 (measured: a clear bottle in a white furnace, mgn 7 and
    # Cycles 6 bounces agree within 0.1 %, mgn 6 is 3.5 % darker).
    bounces = max(0, desc.max_bounces - 1)
    c.max_bounces = bounces
    c.diffuse_bounces = bounces
    c.glossy_bounces = bounces
    c.transmission_bounces = bounces
    c.transparent_max_bounces = bounces
    c.volume_bounces = 0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.pixel_filter_type = "BOX"  # mgn: box filter over the pixel square
    c.filter_width = 1.0
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "NONE"
    scene.render.image_settings.color_mode = "RGB"

    # camera: OpenCV pinhole -> Blender (sensor fit horizontal, shift in units of the width)
    cam = desc.camera
    cd = bpy.data.cameras.new("cam")
    cd.sensor_fit = "HORIZONTAL"
    cd.sensor_width = 36.0
    cd.lens = cam.fx * cd.sensor_width / cam.width
    scene.render.pixel_aspect_x = 1.0
    scene.render.pixel_aspect_y = cam.fx / cam.fy if cam.fy else 1.0
    cd.shift_x = -(cam.cx - cam.width / 2.0) / max(cam.width, cam.height)
    cd.shift_y = (cam.cy - cam.height / 2.0) / max(cam.width, cam.height)
    cd.clip_start = 0.01
    cd.clip_end = 100.0
    co = bpy.data.objects.new("cam", cd)
    co.matrix_world = Matrix((cam.X_WC @ CV_TO_BLENDER).tolist())
    scene.collection.objects.link(co)
    scene.camera = co
    scene.render.resolution_x = cam.width
    scene.render.resolution_y = cam.height
    scene.render.resolution_percentage = 100

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (*desc.environment, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    scene.world = world

    tex_cache: dict[int, Any] = {}
    for item in desc.items:
        for k, part in enumerate(item.parts):
            me = _blender_mesh(f"{item.name}_{item.instance_id}_{k}", part)
            me.materials.append(_blender_material(part.material, tmp, tex_cache))
            ob = bpy.data.objects.new(me.name, me)
            ob.matrix_world = Matrix(np.asarray(item.X_WO).tolist())
            ob.pass_index = item.instance_id
            scene.collection.objects.link(ob)
    for i, light in enumerate(desc.lights):
        sx, sy = light.size[0] / 2, light.size[1] / 2
        V = np.array([[-sx, -sy, 0], [sx, -sy, 0], [sx, sy, 0], [-sx, sy, 0]], np.float64)
        part = Part(V, np.array([[0, 1, 2], [0, 2, 3]], np.int32), None, None)  # type: ignore[arg-type]
        me = _blender_mesh(f"light{i}", part)
        me.materials.append(_blender_emitter(light.radiance))
        ob = bpy.data.objects.new(me.name, me)
        ob.matrix_world = Matrix(light.X_WL.tolist())
        ob.pass_index = 10_000
        scene.collection.objects.link(ob)
    return scene


def _blender_mesh(name: str, part: Part) -> Any:
    import bpy

    used = np.unique(part.faces)
    remap = np.full(len(part.vertices), -1, np.int64)
    remap[used] = np.arange(len(used))
    V = part.vertices[used]
    F = remap[part.faces]
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(V))
    me.vertices.foreach_set("co", V.astype(np.float32).ravel())
    me.loops.add(3 * len(F))
    me.loops.foreach_set("vertex_index", F.astype(np.int32).ravel())
    me.polygons.add(len(F))
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * len(F), 3, dtype=np.int32))
    if part.uvs is not None:
        uv = me.uv_layers.new(name="uv")
        uv.data.foreach_set("uv", part.uvs[used][F].astype(np.float32).ravel())
    me.update()
    if part.normals is None:
        me.shade_flat()
    else:
        me.shade_smooth()
        me.normals_split_custom_set(part.normals.reshape(-1, 3).astype(np.float32).tolist())
    return me


def _blender_emitter(radiance: tuple[float, float, float]) -> Any:
    """One-sided emitter: Emission(radiance) on the front face, black on the back."""
    import bpy

    mat = bpy.data.materials.new("emitter")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*radiance, 1.0)
    em.inputs["Strength"].default_value = 1.0
    black = nt.nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(em.outputs["Emission"], mix.inputs[1])
    nt.links.new(black.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    if hasattr(mat, "emission_sampling"):
        mat.emission_sampling = "FRONT"
    return mat


def _blender_material(pm: Pbr, tmp: Path, cache: dict[int, Any]) -> Any:
    """PbrMaterial -> Principled BSDF (base colour x sRGB texture, metallic, roughness, IOR,
    transmission, emission)."""
    import bpy

    mat = bpy.data.materials.new("pbr")
    mat.use_nodes = True
    nt = mat.node_tree
    bsdf = nt.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*pm.base_color, 1.0)
    bsdf.inputs["Metallic"].default_value = pm.metallic
    bsdf.inputs["Roughness"].default_value = pm.roughness
    bsdf.inputs["IOR"].default_value = pm.ior
    bsdf.inputs["Transmission Weight"].default_value = pm.transmission
    # glTF's specular layer: F0 from the IOR, white tint (Principled's defaults do the same).
    bsdf.inputs["Emission Color"].default_value = (*pm.emission, 1.0)
    bsdf.inputs["Emission Strength"].default_value = 1.0 if any(pm.emission) else 0.0
    if pm.texture is not None:
        key = id(pm.texture)
        if key not in cache:
            path = tmp / f"tex{len(cache)}.png"
            path.write_bytes(_png_bytes(pm.texture))
            img = bpy.data.images.load(str(path))
            img.colorspace_settings.name = "sRGB"
            cache[key] = img
        tex = nt.nodes.new("ShaderNodeTexImage")
        tex.image = cache[key]
        tex.interpolation = "Linear"
        mul = nt.nodes.new("ShaderNodeMix")
        mul.data_type = "RGBA"
        mul.blend_type = "MULTIPLY"
        mul.inputs["Factor"].default_value = 1.0
        mul.inputs["B"].default_value = (*pm.base_color, 1.0)
        nt.links.new(tex.outputs["Color"], mul.inputs["A"])
        nt.links.new(mul.outputs["Result"], bsdf.inputs["Base Color"])
    return mat


def cycles_render(
    scene: Any, spp: int, out: Path, denoise: bool = False, seed: int = 0
) -> np.ndarray:
    """Renders with ``spp`` samples; returns (H, W, 3) float32 linear radiance, top row first."""
    import bpy

    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.cycles.use_denoising = denoise
    if denoise:
        scene.cycles.denoiser = "OPENIMAGEDENOISE"
        scene.cycles.denoising_input_passes = "RGB_ALBEDO_NORMAL"
        scene.cycles.denoising_prefilter = "ACCURATE"
    scene.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)
    return _read_exr(out, scene.render.resolution_x, scene.render.resolution_y)


def _read_exr(path: Path, w: int, h: int) -> np.ndarray:
    import bpy

    img = bpy.data.images.load(str(path))
    px = np.empty(w * h * 4, np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[::-1, :, :3].copy()


def cycles_ids(desc: SceneDesc, tmp: Path, threads: int) -> np.ndarray:
    """Instance id per pixel from Cycles: every object emits its id (no lights, black world),
    one sample at the pixel centre (a 0.01 px Gaussian filter)."""
    import bpy

    scene = cycles_scene(desc, tmp, threads)
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    for ob in scene.objects:
        if ob.type != "MESH":
            continue
        mat = bpy.data.materials.new(f"id{ob.pass_index}")
        mat.use_nodes = True
        nt = mat.node_tree
        nt.nodes.clear()
        out = nt.nodes.new("ShaderNodeOutputMaterial")
        em = nt.nodes.new("ShaderNodeEmission")
        v = float(ob.pass_index)
        em.inputs["Color"].default_value = (v, v, v, 1.0)
        nt.links.new(em.outputs["Emission"], out.inputs["Surface"])
        ob.data.materials.clear()
        ob.data.materials.append(mat)
    scene.cycles.pixel_filter_type = "GAUSSIAN"
    scene.cycles.filter_width = 0.01
    scene.cycles.max_bounces = 0
    img = cycles_render(scene, 1, tmp / "ids.exr")
    return np.rint(img[..., 0]).astype(np.int32)


# ----------------------------------------------------------------------------------------------
# Mitsuba 3

CV_TO_MITSUBA = np.diag([-1.0, -1.0, 1.0, 1.0])  # Mitsuba camera: +z forward, +y up, +x left


def _libllvm() -> str | None:
    """A libLLVM that Dr.Jit 1.5 can use (>= 16; LLVM 15 aborts in its code generator):
    $DRJIT_LIBLLVM_PATH, else Debian's libllvm19..16 (apt-get install libllvm19)."""
    if os.environ.get("DRJIT_LIBLLVM_PATH"):
        return os.environ["DRJIT_LIBLLVM_PATH"]
    for v in (19, 18, 17, 16):
        for name in (f"libLLVM-{v}.so", f"libLLVM.so.{v}.1"):
            path = Path("/usr/lib/x86_64-linux-gnu") / name
            if path.exists():
                return str(path)
    return None


def mitsuba_variant() -> str:
    """llvm_ad_rgb (vectorised, JIT through libLLVM >= 16) when such a libLLVM is installed,
    else scalar_rgb. Must run before the first ``import mitsuba``."""
    lib = _libllvm()
    if lib:
        os.environ["DRJIT_LIBLLVM_PATH"] = lib
    import mitsuba as mi

    for v in (("llvm_ad_rgb",) if lib else ()) + ("scalar_rgb",):
        if v in mi.variants():
            try:
                mi.set_variant(v)
                return v
            except Exception:  # libLLVM not loadable: next variant
                continue
    raise RuntimeError(f"no CPU variant of Mitsuba loads (have {mi.variants()})")


def _write_ply(
    path: Path, V: np.ndarray, F: np.ndarray, uv: np.ndarray | None, N: np.ndarray | None = None
) -> None:
    nv = len(V)
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {nv}"]
    head += ["property float x", "property float y", "property float z"]
    if N is not None:
        head += ["property float nx", "property float ny", "property float nz"]
    if uv is not None:
        head += ["property float u", "property float v"]
    head += [f"element face {len(F)}", "property list uchar int vertex_indices", "end_header"]
    vert = V.astype(np.float32)
    if N is not None:
        vert = np.concatenate([vert, N.astype(np.float32)], axis=1)
    if uv is not None:
        vert = np.concatenate([vert, uv.astype(np.float32)], axis=1)
    faces = np.zeros(len(F), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"] = 3
    faces["i"] = F
    with Path(path).open("wb") as f:
        f.write(("\n".join(head) + "\n").encode())
        f.write(np.ascontiguousarray(vert, "<f4").tobytes())
        f.write(faces.tobytes())


def mitsuba_dict(desc: SceneDesc, tmp: Path, spp: int, ids: bool = False) -> dict[str, Any]:
    """The scene as a Mitsuba 3 scene dict (mi.load_dict). ``ids``: objects emit their id."""
    import mitsuba as mi

    cam = desc.camera
    d: dict[str, Any] = {"type": "scene"}
    d["integrator"] = {
        "type": "path",
        "max_depth": 1 if ids else desc.max_bounces + 1,  # Mitsuba counts the camera segment
        "rr_depth": 4,
        "hide_emitters": False,
    }
    fov = math.degrees(2.0 * math.atan(cam.width / (2.0 * cam.fx)))
    d["sensor"] = {
        "type": "perspective",
        "fov": fov,
        "fov_axis": "x",
        "principal_point_offset_x": -(cam.cx - cam.width / 2.0) / cam.width,
        "principal_point_offset_y": -(cam.cy - cam.height / 2.0) / cam.height,
        "near_clip": 0.01,
        "far_clip": 100.0,
        "to_world": mi.ScalarTransform4f((cam.X_WC @ CV_TO_MITSUBA).tolist()),
        "sampler": {"type": "independent", "sample_count": spp},
        "film": {
            "type": "hdrfilm",
            "width": cam.width,
            "height": cam.height,
            "pixel_format": "rgb",
            "component_format": "float32",
            "rfilter": {"type": "gaussian", "stddev": 0.05} if ids else {"type": "box"},
        },
    }
    if not ids:
        d["env"] = {
            "type": "constant",
            "radiance": {"type": "rgb", "value": list(desc.environment)},
        }
    tex_cache: dict[int, Any] = {}
    n = 0
    for item in desc.items:
        for part in item.parts:
            # one vertex per face corner, with mgn's per-corner shading normal
            corners = part.faces.reshape(-1)
            path = tmp / f"m{n}.ply"
            uv = None
            if part.uvs is not None:  # Mitsuba's bitmap has v = 0 at the bottom row
                uv = part.uvs[corners].astype(np.float32)
                uv[:, 1] = 1.0 - uv[:, 1]
            nrm = None if part.normals is None else part.normals.reshape(-1, 3)
            tri = np.arange(len(corners), dtype=np.int32).reshape(-1, 3)
            _write_ply(path, part.vertices[corners], tri, uv, nrm)
            shape: dict[str, Any] = {
                "type": "ply",
                "filename": str(path),
                "face_normals": nrm is None,
                "to_world": mi.ScalarTransform4f(np.asarray(item.X_WO).tolist()),
            }
            if ids:
                shape["bsdf"] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}}
                v = float(item.instance_id)
                shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": [v] * 3}}
            else:
                shape["bsdf"] = _mitsuba_bsdf(part.material, tex_cache)
                if any(part.material.emission):
                    shape["emitter"] = {
                        "type": "area",
                        "radiance": {"type": "rgb", "value": list(part.material.emission)},
                    }
            d[f"shape{n}"] = shape
            n += 1
    if not ids:
        for i, light in enumerate(desc.lights):
            S = np.diag([light.size[0] / 2, light.size[1] / 2, 1.0, 1.0])
            d[f"light{i}"] = {
                "type": "rectangle",
                "to_world": mi.ScalarTransform4f((light.X_WL @ S).tolist()),
                "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.0}},
                "emitter": {
                    "type": "area",
                    "radiance": {"type": "rgb", "value": list(light.radiance)},
                },
            }
    return d


def _mitsuba_bsdf(pm: Pbr, cache: dict[int, Any]) -> dict[str, Any]:
    """PbrMaterial -> Mitsuba ``principled`` (base colour x texture baked into one linear
    bitmap; metallic; roughness (GGX alpha = roughness^2 in both); eta = ior; spec_trans =
    transmission)."""
    import mitsuba as mi

    if pm.texture is not None:
        key = id(pm.texture)
        if key not in cache:
            lin = srgb_to_linear(pm.texture) * np.asarray(pm.base_color, np.float32)
            cache[key] = mi.Bitmap(np.ascontiguousarray(lin, np.float32))
        base: dict[str, Any] = {"type": "bitmap", "bitmap": cache[key], "raw": True}
    else:
        base = {"type": "rgb", "value": list(pm.base_color)}
    return {
        "type": "principled",
        "base_color": base,
        "metallic": pm.metallic,
        "roughness": max(pm.roughness, 1e-3),
        "eta": pm.ior,
        "spec_trans": pm.transmission,
    }


def mitsuba_render(scene: Any, spp: int, seed: int = 0) -> np.ndarray:
    import mitsuba as mi

    img = mi.render(scene, spp=spp, seed=seed)
    return np.asarray(img, np.float32)[..., :3].copy()


def mitsuba_ids(desc: SceneDesc, tmp: Path) -> np.ndarray:
    import mitsuba as mi

    scene = mi.load_dict(mitsuba_dict(desc, tmp, 64, ids=True))
    img = mitsuba_render(scene, 64)
    return np.rint(img[..., 0]).astype(np.int32)
