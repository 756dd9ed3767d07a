"""Views of rotations, skeletons and IK: pyvista scenes, matplotlib figures, ipywidgets controls.

Imported on demand (``import course`` does not load it). The submodules load pyvista,
matplotlib and ipywidgets when first used::

    from course.viz import SkeletonScene, fk_explorer, bvh_player
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

from .backend import configure_environment

configure_environment()

_EXPORTS = {
    "scene": ("SkeletonScene", "show_skeletons", "PALETTE"),
    "frame_scene": ("FrameScene",),
    "figures": (
        "ChainPlot",
        "ConvergenceFigure",
        "JointAngleFigure",
        "SlerpArcFigure",
        "GimbalFigure",
        "convergence_plot",
        "draw_frame",
        "slerp_arc_figure",
    ),
    "rotation_views": ("rotation_explorer", "slerp_explorer"),
    "fk_view": ("fk_explorer",),
    "clip_player": ("bvh_player",),
    "ik_playground_view": ("ik_playground",),
    "full_body_ik_view": ("full_body_ik",),
    "cloth": ("ClothScene", "ClothSimulator", "cloth_simulator"),
    "lqr_view": ("LQRBalanceSimulator", "lqr_balance_simulator"),
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}

__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
