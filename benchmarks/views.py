"""How fast the views answer a slider, headless: value change -> rendered frame.

For each control, the time from setting a widget's value to a rendered frame (math, in-place
mesh update, render and the PNG the notebook shows), beside the naive way: rebuilding the
scene from scratch for the same frame. Also the math alone per event (budget: 2 ms for a
31-joint skeleton or a 7-joint chain) and matplotlib's full redraw against blitting.

    .venv/bin/python benchmarks/views.py
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("PYVISTA_JUPYTER_BACKEND", "static")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import numpy as np  # noqa: E402


def _median_ms(fn: Callable[[int], object], repeat: int = 15) -> float:
    fn(0)  # warm up
    times = []
    for i in range(1, repeat + 1):
        t = time.perf_counter()
        fn(i)
        times.append(time.perf_counter() - t)
    return 1000.0 * float(np.median(times))


def _row(name: str, fast: float, slow: float | None = None) -> None:
    if slow is None:
        print(f"  {name:<44} {fast:9.2f} ms")
    else:
        print(f"  {name:<44} {fast:9.2f} ms   naive {slow:9.2f} ms   x{slow / fast:6.1f}")


def main() -> None:
    from course import data, viz
    from course.rotations import quat_from_euler
    from course.skeleton import chain
    from course.viz.figures import (
        ChainPlot,
        GimbalFigure,
        convergence_plot,
        figure_png,
        slerp_arc_figure,
    )
    from course.viz.frame_scene import FrameScene
    from course.viz.scene import SkeletonScene

    motion = data.load("cmu_12_01_walk")
    sk = motion.skeleton
    arm = chain([1.0] * 7, axes=[0, 0, 1])
    rng = np.random.default_rng(0)

    def rebuild(parents, pose, size=(640, 520)) -> None:  # the naive way: a new scene per event
        scene = SkeletonScene(window_size=size)
        scene.add_skeleton(parents, pose)
        scene.screenshot()
        scene.close()

    def rebuild_frames(n: int, size) -> None:
        scene = FrameScene(n, window_size=size)
        scene.screenshot()
        scene.close()

    print("math per event (budget 2 ms)")
    local, root = motion.local_rotations[100], motion.root_positions[100]
    _row(f"FK, {sk.n_joints} joints (CMU walk)",
         _median_ms(lambda _i: sk.forward_kinematics(local, root), 50))
    import course.ik

    ident = np.tile([1.0, 0, 0, 0], (arm.n_joints, 1))
    for method in ("ccd", "fabrik", "dls"):
        _row(f"IK {method}, 7-joint chain, solve + record",
             _median_ms(lambda i, m=method: course.ik.solve(
                 arm, ident, np.zeros(3), {"end_effector": [3.0, 4.0 + 0.01 * i, 0.0]},
                 method=m, record=True), 20))
    hands = {"LeftHand": None, "RightHand": None}
    pos, _ = sk.forward_kinematics(local, root)
    for name in hands:
        hands[name] = pos[sk.index(name)] + [2.0, 1.0, 0.0]
    _row("IK dls, CMU walk, two hands",
         _median_ms(lambda i: course.ik.solve(sk, local, root, {
             k: v + [0, 0.01 * i, 0] for k, v in hands.items()}, method="dls"), 10))

    print("\nvalue change -> rendered frame (static backend: render + PNG),"
          " beside rebuilding the views for the same event")
    ex = viz.fk_explorer(sk, local, root)
    slider = ex.sliders["LeftArm.0"]
    fast = _median_ms(lambda i: setattr(slider, "value", float(i % 90)))
    _row("fk_explorer (38 joints, axes)", fast, _median_ms(
        lambda _i: rebuild(sk.parents, ex.positions), 5))
    ex.close()

    player = viz.bvh_player(motion, curves={"hips y": motion.root_positions[:, 1] / 100})
    fast = _median_ms(lambda i: setattr(player.sliders["frame"], "value", 7 * i))
    _row("bvh_player frame (+ curve cursor)", fast, _median_ms(
        lambda i: rebuild(sk.parents, player.positions[7 * i], (720, 480)), 5))
    player.close()

    rot = viz.rotation_explorer()
    _row("rotation_explorer (frame + gimbal figure)",
         _median_ms(lambda i: setattr(rot.sliders["angle0"], "value", float(i))),
         _median_ms(lambda i: (rebuild_frames(1, (380, 340)),
                               GimbalFigure("XYZ", (0.01 * i, 0, 0)).png()), 5))
    rot.close()

    se = viz.slerp_explorer()
    _row("slerp_explorer t (3 frames + arc marker)",
         _median_ms(lambda i: setattr(se.sliders["t"], "value", 0.05 * (i % 20))),
         _median_ms(lambda i: (rebuild_frames(3, (780, 330)), figure_png(
             slerp_arc_figure(se.q0, se.q1, t=0.05 * (i % 20)))), 5))
    _row("slerp_explorer end rotation (arc paths)",
         _median_ms(lambda i: setattr(se.sliders["end1"], "value", 100.0 + i)),
         _median_ms(lambda i: (rebuild_frames(3, (780, 330)), figure_png(
             slerp_arc_figure(se.q0, quat_from_euler([0.3, 1.7 + 0.01 * i, 1.0], "XYZ")))), 5))
    se.close()

    pg = viz.ik_playground(arm, methods=["ccd", "fabrik", "dls"])

    def naive_ik(i: int) -> None:
        r = course.ik.solve(arm, ident, np.zeros(3), {"joint6": pg.target}, method="dls",
                            record=True)
        rebuild(arm.parents, r.positions, (640, 500))
        figure = convergence_plot({"dls": r.residuals}, tol=1e-4).figure
        figure.canvas.draw()
        figure_png(figure)

    fast = _median_ms(lambda i: setattr(pg.sliders["y"], "value", 3.0 + 0.05 * i))
    _row("ik_playground target (dls + convergence plot)", fast, _median_ms(naive_ik, 5))
    replay = _median_ms(lambda i: setattr(pg.sliders["iteration"], "value", i % len(pg.frames)))
    _row("ik_playground iteration replay", replay, _median_ms(
        lambda i: rebuild(arm.parents, pg.frames[i % len(pg.frames)], (640, 500)), 5))
    pg.close()

    fb = viz.full_body_ik(motion, 100)
    y0 = fb.sliders["y"].value
    fast = _median_ms(lambda i: setattr(fb.sliders["y"], "value", y0 + 0.1 * (i % 20)))
    _row("full_body_ik target (dls, two effectors)", fast, _median_ms(
        lambda _i: rebuild(sk.parents, fb.result.positions), 5))
    fb.close()

    print("\nmatplotlib, 30 bones")
    parents = np.concatenate([[-1], np.arange(30)])
    pose = np.cumsum(rng.normal(size=(31, 3)), axis=0)
    for dims in (2, 3):
        plot = ChainPlot(parents, pose, dims=dims)
        update = _median_ms(lambda i, p=plot: p.update(pose + 0.01 * i))
        full = _median_ms(lambda i, p=plot: (p.update(pose + 0.01 * i), p.full_redraw()))
        _row(f"{dims}D: update (blit) vs full redraw", update, full)


if __name__ == "__main__":
    main()
