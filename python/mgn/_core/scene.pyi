"""
mgn/scene: drop, layout, scene grasps, per-view labels.
"""

from __future__ import annotations

import collections.abc
import typing

import numpy
import numpy.typing

import mgn._core.geometry
import mgn._core.grasp
import mgn._core.render

__all__: list[str] = [
    "SUCTION_TOOL_OFFSET",
    "DropHullCacheInfo",
    "DropOptions",
    "DropResult",
    "LayoutArrays",
    "ObjectGraspLabels",
    "PlacedGraspArrays",
    "SceneGraspModel",
    "SceneGraspOptions",
    "SuctionTool",
    "ToolCollisionArrays",
    "ViewGraspArrays",
    "ViewLabelArrays",
    "ViewLabelModel",
    "clear_drop_hull_cache",
    "com_heatmap_prediction",
    "compute_layout",
    "drop_hull_cache_info",
    "drop_objects",
    "set_drop_hull_cache_capacity",
]

class DropOptions:
    """
    Options of drop_objects (mgn/scene/drop.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """

    polyhedral_contacts: bool
    remove_unsettled: bool
    tote_collision: str
    two_friction_directions: bool
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def angular_damping(self) -> float: ...
    @angular_damping.setter
    def angular_damping(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def angular_rest(self) -> float: ...
    @angular_rest.setter
    def angular_rest(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def collision_margin(self) -> float: ...
    @collision_margin.setter
    def collision_margin(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def contact_distance(self) -> float: ...
    @contact_distance.setter
    def contact_distance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def dt(self) -> float: ...
    @dt.setter
    def dt(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def gravity(self) -> float: ...
    @gravity.setter
    def gravity(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def guard_height(self) -> float: ...
    @guard_height.setter
    def guard_height(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def hull_tolerance(self) -> float: ...
    @hull_tolerance.setter
    def hull_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def linear_rest(self) -> float: ...
    @linear_rest.setter
    def linear_rest(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def max_hull_vertices(self) -> int: ...
    @max_hull_vertices.setter
    def max_hull_vertices(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def max_time(self) -> float: ...
    @max_time.setter
    def max_time(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def resettle_time(self) -> float: ...
    @resettle_time.setter
    def resettle_time(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def rest_time(self) -> float: ...
    @rest_time.setter
    def rest_time(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def rolling_friction(self) -> float: ...
    @rolling_friction.setter
    def rolling_friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def seed(self) -> int: ...
    @seed.setter
    def seed(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def solver_iterations(self) -> int: ...
    @solver_iterations.setter
    def solver_iterations(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def tote_friction(self) -> float: ...
    @tote_friction.setter
    def tote_friction(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def tote_restitution(self) -> float: ...
    @tote_restitution.setter
    def tote_restitution(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def window_max(self) -> tuple[float, float, float]: ...
    @window_max.setter
    def window_max(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...
    @property
    def window_min(self) -> tuple[float, float, float]: ...
    @window_min.setter
    def window_min(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...

class DropResult:
    """
    drop_objects() result: one row per input object, in input order.
    """
    @property
    def X_WO(self) -> numpy.ndarray:
        """
        (N,4,4) float64 settled poses, m
        """
    @property
    def X_WO_release(self) -> numpy.ndarray:
        """
        (N,4,4) float64 release (or start) poses, m
        """
    @property
    def contacts(self) -> numpy.ndarray:
        """
        (N,) uint32 tote contact flags (bits -x, +x, -y, +y walls, floor)
        """
    @property
    def max_penetration(self) -> float:
        """
        deepest contact penetration on the simulated hulls, m
        """
    @property
    def object_settled(self) -> numpy.ndarray:
        """
        (N,) bool: at rest when the simulation stopped
        """
    @property
    def resettle_rounds(self) -> int: ...
    @property
    def settled(self) -> bool:
        """
        every remaining object came to rest
        """
    @property
    def simulated_time(self) -> float:
        """
        s
        """
    @property
    def status(self) -> numpy.ndarray:
        """
        (N,) int32: 0 kept, 1 left the tote, 2 not settled
        """
    @property
    def steps(self) -> int: ...

class DropHullCacheInfo:
    """
    State of the drop's cache of prepared object hulls (mgn/scene/drop.hpp).
    """
    @property
    def bytes(self) -> int:
        """
        estimated memory of the entries
        """
    @property
    def capacity(self) -> int:
        """
        bytes; 0: nothing is cached
        """
    @property
    def entries(self) -> int: ...
    @property
    def evictions(self) -> int:
        """
        entries evicted for the capacity (since the last clear)
        """
    @property
    def hits(self) -> int:
        """
        objects whose hulls came from the cache (since the last clear)
        """
    @property
    def misses(self) -> int:
        """
        objects whose hulls were prepared (since the last clear)
        """

class LayoutArrays:
    """
    compute_layout() result (mgn/scene/layout.hpp): 0-based object indices; rel_* are the relations sorted by (child, parent).
    """
    @property
    def classes_unique(self) -> bool: ...
    @property
    def complete(self) -> numpy.ndarray:
        """
        (N,) bool
        """
    @property
    def difficulty(self) -> int:
        """
        1..5
        """
    @property
    def layer(self) -> numpy.ndarray:
        """
        (N,) int8
        """
    @property
    def max_occlusion(self) -> float: ...
    @property
    def num_layers(self) -> int: ...
    @property
    def num_regions(self) -> numpy.ndarray:
        """
        (N,) int32
        """
    @property
    def order(self) -> numpy.ndarray:
        """
        picking order, int32 1-based ids
        """
    @property
    def rel_child(self) -> numpy.ndarray:
        """
        (R,) int32 0-based
        """
    @property
    def rel_depth_diff(self) -> numpy.ndarray:
        """
        (R,) float64 m
        """
    @property
    def rel_edge_size(self) -> numpy.ndarray:
        """
        (R,) int32 px
        """
    @property
    def rel_parent(self) -> numpy.ndarray:
        """
        (R,) int32 0-based
        """
    @property
    def rel_seen_px(self) -> numpy.ndarray:
        """
        (R,) int64 px
        """
    @property
    def relation(self) -> numpy.ndarray:
        """
        (N,N) int8 relation matrix
        """
    @property
    def total_covered_edge(self) -> numpy.ndarray:
        """
        (N,) int64 px
        """
    @property
    def visible(self) -> numpy.ndarray:
        """
        (N,) bool
        """
    @property
    def visible_px(self) -> numpy.ndarray:
        """
        (N,) int64
        """

class ObjectGraspLabels:
    """
    Object-level grasp labels of one object, the input of SceneGraspModel (mgn/scene/scene_grasps.hpp). Object frame O, metres; every argument is optional (None: no labels of that kind, or NaN scores).
    """
    def __init__(
        self,
        pj_p1: typing.Any | None = None,
        pj_closing: typing.Any = None,
        pj_approach: typing.Any = None,
        pj_width: typing.Any = None,
        pj_score_analytical: typing.Any = None,
        pj_score_simulation: typing.Any = None,
        suction_points: typing.Any = None,
        suction_approach: typing.Any = None,
        suction_score_analytical: typing.Any = None,
        suction_score_simulation: typing.Any = None,
    ) -> None: ...
    @property
    def pj_approach(self) -> numpy.ndarray:
        """
        (M,3) float64 unit approach direction, object frame
        """
    @property
    def pj_closing(self) -> numpy.ndarray:
        """
        (M,3) float64 unit closing direction v (p2 = p1 + w v), object frame
        """
    @property
    def pj_p1(self) -> numpy.ndarray:
        """
        (M,3) float64 first contact p1 of each parallel-jaw grasp, object frame, m
        """
    @property
    def pj_score_analytical(self) -> numpy.ndarray:
        """
        (M,) or (0,) float32 analytical score in [0, 1]
        """
    @property
    def pj_score_simulation(self) -> numpy.ndarray:
        """
        (M,) or (0,) float32 simulation score in [0, 1]
        """
    @property
    def pj_width(self) -> numpy.ndarray:
        """
        (M,) float32 contact width w, m
        """
    @property
    def suction_approach(self) -> numpy.ndarray:
        """
        (K,3) float32 approach directions into the surface, object frame
        """
    @property
    def suction_points(self) -> numpy.ndarray:
        """
        (K,3) float32 suction contacts, object frame, m
        """
    @property
    def suction_score_analytical(self) -> numpy.ndarray:
        """
        (K,) or (0,) float32 seal score in [0, 1]
        """
    @property
    def suction_score_simulation(self) -> numpy.ndarray:
        """
        (K,) or (0,) float32 simulation score in [0, 1]
        """

class SuctionTool:
    """
    Suction tool geometry behind the cup body for the scene collision check (mgn/scene/scene_grasps.hpp, m); defaults are the C++ struct's.
    """
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def clearance(self) -> float:
        """
        gap between the contact and the bottom of the cup body, m
        """
    @clearance.setter
    def clearance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shaft_length(self) -> float:
        """
        m
        """
    @shaft_length.setter
    def shaft_length(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def shaft_radius(self) -> float:
        """
        m
        """
    @shaft_radius.setter
    def shaft_radius(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class SceneGraspOptions:
    """
    Options of SceneGraspModel (mgn/scene/scene_grasps.hpp, SI units); the defaults are the C++ struct's, validate() checks the ranges.
    """

    pj_wrench: mgn._core.grasp.PjWrenchOptions
    suction_wrench: mgn._core.grasp.SuctionWrenchOptions
    tool: SuctionTool
    def __init__(self) -> None: ...
    def validate(self) -> None:
        """
        Raises InvalidArgumentError naming the first field out of its range.
        """
    @property
    def approach_step(self) -> float:
        """
        largest spacing of the poses checked between offsets, m
        """
    @approach_step.setter
    def approach_step(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def first_collision_only(self) -> bool:
        """
        stop at each label grasp's first colliding pose (hit of the later offsets = -2, not checked)
        """
    @first_collision_only.setter
    def first_collision_only(self, arg0: bool) -> None: ...
    @property
    def gravity_world(self) -> tuple[float, float, float]:
        """
        direction of gravity in the world (tote frame), normalised by the model
        """
    @gravity_world.setter
    def gravity_world(
        self,
        arg1: tuple[
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
            typing.SupportsFloat | typing.SupportsIndex,
        ],
    ) -> None: ...
    @property
    def near_plane(self) -> float:
        """
        m
        """
    @near_plane.setter
    def near_plane(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...
    @property
    def num_threads(self) -> int:
        """
        0 = all hardware threads
        """
    @num_threads.setter
    def num_threads(self, arg0: typing.SupportsInt | typing.SupportsIndex) -> None: ...
    @property
    def offsets(self) -> list[float]:
        """
        distances back along the approach where the tool is checked, m
        """
    @offsets.setter
    def offsets(
        self, arg0: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex]
    ) -> None: ...
    @property
    def visibility_tolerance(self) -> float:
        """
        m
        """
    @visibility_tolerance.setter
    def visibility_tolerance(self, arg0: typing.SupportsFloat | typing.SupportsIndex) -> None: ...

class PlacedGraspArrays:
    """
    SceneGraspModel.pj / .suction (mgn/scene/scene_grasps.hpp): world-frame grasps of every object; mgn.view_labels.grasps.PlacedGrasps documents each array.
    """
    @property
    def colliding(self) -> numpy.ndarray: ...
    @property
    def collision_obstacle(self) -> numpy.ndarray: ...
    @property
    def collision_part(self) -> numpy.ndarray: ...
    @property
    def contact_poses(self) -> numpy.ndarray: ...
    @property
    def contacts(self) -> numpy.ndarray: ...
    @property
    def hit(self) -> numpy.ndarray: ...
    @property
    def object_index(self) -> numpy.ndarray: ...
    @property
    def score_analytical(self) -> numpy.ndarray: ...
    @property
    def score_simulation(self) -> numpy.ndarray: ...
    @property
    def score_wrench(self) -> numpy.ndarray: ...
    @property
    def second_contacts(self) -> numpy.ndarray: ...
    @property
    def tool_poses(self) -> numpy.ndarray: ...
    @property
    def width(self) -> numpy.ndarray: ...

class ToolCollisionArrays:
    """
    SceneGraspModel.collides(): colliding (M,) bool, hit (M, K) int32.
    """
    @property
    def colliding(self) -> numpy.ndarray: ...
    @property
    def hit(self) -> numpy.ndarray: ...

class ViewGraspArrays:
    """
    SceneGraspModel.view_grasps(): row indices and camera-frame (N,4,4) tool and contact poses of the grasps kept in a view.
    """
    @property
    def pj_contact(self) -> numpy.ndarray: ...
    @property
    def pj_index(self) -> numpy.ndarray: ...
    @property
    def pj_tool(self) -> numpy.ndarray: ...
    @property
    def suction_contact(self) -> numpy.ndarray: ...
    @property
    def suction_index(self) -> numpy.ndarray: ...
    @property
    def suction_tool(self) -> numpy.ndarray: ...

class SceneGraspModel:
    """
    Per-scene grasp model: placement, collisions and wrench scores at construction; view_grasps per camera (see mgn/scene/scene_grasps.hpp).
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[mgn._core.geometry.Mesh],
        poses: typing.Any,
        masses: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
        coms: typing.Any,
        labels: collections.abc.Sequence[ObjectGraspLabels],
        tote: mgn._core.geometry.Mesh,
        X_WT: typing.Any,
        gripper: mgn._core.grasp.ParallelJawGripper,
        cup: mgn._core.grasp.Cup,
        options: SceneGraspOptions = ...,
    ) -> None: ...
    def collides(
        self,
        kind: str,
        X_W_contact: typing.Any,
        width: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
        target_object: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
        check_target_at_grasp: bool = False,
    ) -> ToolCollisionArrays:
        """
        Collision of arbitrary grasp (contact-frame) poses with the labels' test: colliding (M,) bool and hit (M, K) int32.
        """
    def pj(self) -> PlacedGraspArrays:
        """
        Parallel-jaw grasps in the world (PlacedGraspArrays).
        """
    def suction(self) -> PlacedGraspArrays:
        """
        Suction grasps in the world (PlacedGraspArrays).
        """
    def view_grasps(
        self, K: mgn._core.render.Intrinsics, X_WC: typing.Any, seen: typing.Any
    ) -> ViewGraspArrays:
        """
        Grasps kept in a view: row indices and camera-frame poses.
        """
    def visible(
        self, K: mgn._core.render.Intrinsics, X_WC: typing.Any, points: typing.Any
    ) -> numpy.ndarray:
        """
        (N,) bool: whether each world point is visible from the camera.
        """
    @property
    def num_objects(self) -> int: ...
    @property
    def offsets(self) -> list[float]: ...

class ViewLabelArrays:
    """
    ViewLabelModel.label_view() result (mgn/scene/view_labels.hpp); mgn.view_labels.objects.ViewObjectLabels documents each array.
    """
    @property
    def X_CO(self) -> numpy.ndarray: ...
    @property
    def amodal(self) -> numpy.ndarray: ...
    @property
    def amodal_pixels(self) -> numpy.ndarray: ...
    @property
    def bbox_loose(self) -> numpy.ndarray: ...
    @property
    def bbox_tight(self) -> numpy.ndarray: ...
    @property
    def com_heatmap(self) -> numpy.ndarray: ...
    @property
    def com_object(self) -> numpy.ndarray: ...
    @property
    def com_points(self) -> numpy.ndarray: ...
    @property
    def com_visible(self) -> numpy.ndarray: ...
    @property
    def keypoint_object(self) -> numpy.ndarray: ...
    @property
    def keypoints(self) -> numpy.ndarray: ...
    @property
    def occluded_keypoint_object(self) -> numpy.ndarray: ...
    @property
    def occluded_keypoints(self) -> numpy.ndarray: ...
    @property
    def occlusion(self) -> numpy.ndarray: ...
    @property
    def occlusion_map(self) -> numpy.ndarray: ...
    @property
    def semantic(self) -> numpy.ndarray: ...
    @property
    def visible(self) -> numpy.ndarray: ...
    @property
    def visible_pixels(self) -> numpy.ndarray: ...

class ViewLabelModel:
    """
    Ray-tracing model of one scene for per-view object labels.
    """
    def __init__(
        self,
        meshes: collections.abc.Sequence[mgn._core.geometry.Mesh],
        poses: typing.Any,
        category_ids: collections.abc.Sequence[typing.SupportsInt | typing.SupportsIndex],
        keypoints: collections.abc.Sequence[typing.Any],
        com_points: collections.abc.Sequence[typing.Any],
        coms: typing.Any,
        tote: mgn._core.geometry.Mesh | None = None,
        X_W_tote: typing.Any = None,
    ) -> None: ...
    def label_view(
        self,
        K: mgn._core.render.Intrinsics,
        X_WC: typing.Any,
        instance_image: typing.Any,
        keypoint_tolerance: typing.SupportsFloat | typing.SupportsIndex = 0.002,
        keypoints: bool = True,
        num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
        depth: typing.Any = None,
    ) -> ViewLabelArrays: ...
    @property
    def has_tote(self) -> bool: ...
    @property
    def num_objects(self) -> int: ...

def clear_drop_hull_cache() -> None:
    """
    Drops every entry of the drop's hull cache and resets its counters.
    """

def com_heatmap_prediction(
    depth_m: typing.Any,
    instances: typing.Any,
    X_WC: typing.Any,
    fx: typing.SupportsFloat | typing.SupportsIndex,
    fy: typing.SupportsFloat | typing.SupportsIndex,
    cx: typing.SupportsFloat | typing.SupportsIndex,
    cy: typing.SupportsFloat | typing.SupportsIndex,
    com_parameters: typing.Any,
) -> numpy.typing.NDArray[numpy.float32]:
    """
    (H, W) float32 CoM heat map predicted from the noise-free depth (m), see mgn/scene/view_labels.hpp and docs/format.md.
    """

def compute_layout(
    visible: typing.Any,
    amodal: typing.Any,
    depth: typing.Any,
    categories: typing.Any,
    occlusion: typing.Any,
    min_overlap_px: typing.SupportsInt | typing.SupportsIndex = 10,
    min_overlap_fraction: typing.SupportsFloat | typing.SupportsIndex = 0.1,
    min_region_px: typing.SupportsInt | typing.SupportsIndex = 10,
    min_region_fraction: typing.SupportsFloat | typing.SupportsIndex = 0.005,
    max_occlusion_level1: typing.SupportsFloat | typing.SupportsIndex = 0.05,
    num_threads: typing.SupportsInt | typing.SupportsIndex = 0,
) -> LayoutArrays:
    """
    Layout labels of one view (see mgn/scene/layout.hpp); use mgn.view_labels.layout.compute_layout.
    """

def drop_hull_cache_info() -> DropHullCacheInfo:
    """
    The state of the drop's cache of prepared object hulls (mgn/scene/drop.hpp).
    """

def drop_objects(
    parts: collections.abc.Sequence[collections.abc.Sequence[mgn._core.geometry.Mesh]],
    masses: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    coms: typing.Any,
    inertias: typing.Any,
    frictions: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    restitutions: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    names: collections.abc.Sequence[str],
    tote: mgn._core.geometry.Mesh,
    tote_box: collections.abc.Sequence[typing.SupportsFloat | typing.SupportsIndex],
    options: DropOptions,
    X_WO_start: typing.Any = None,
) -> DropResult: ...
def set_drop_hull_cache_capacity(bytes: typing.SupportsInt | typing.SupportsIndex) -> None:
    """
    Sets the capacity of the drop's hull cache (estimated bytes; 0: cache nothing) and evicts the least recently used entries down to it.
    """

SUCTION_TOOL_OFFSET: float = 0.1321
