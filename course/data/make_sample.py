r"""Generate ``samples/wave.bvh``, the package's own motion: a person waving hello.

Run ``python -m course.data.make_sample`` to (re)write the file; the tests check that this
reproduces it byte for byte, so the sample is provably of our own making.

The skeleton: 19 joints plus 5 End Sites, y up, facing +z (its left is +x), in the units of
the CMU clips (ASF length units, 1 unit = 1/0.45 inch = 5.64 cm; the hips stand 16.5 units
= 0.93 m high), every joint animated with ``Zrotation Yrotation Xrotation`` as in CMU.

The motion, 4 s at 30 fps, periodic with period 4 s so that it loops seamlessly (every term
has a frequency that is a multiple of :math:`\omega_0 = 2\pi / 4\,\mathrm s`):

- the hips shift side to side, :math:`d(t) = 0.5 \sin\omega_0 t`, with both feet planted:
  each straight leg of length :math:`L` tilts by :math:`\theta = -\arcsin(d/L)` (so the
  foot stays put, :math:`L\sin\theta = -d`), the hips drop by :math:`L(1-\cos\theta)` and the
  ankle turns back by :math:`-\theta` to keep the foot flat;
- the right arm is raised and the forearm waves at 1.5 Hz, the hand lagging behind;
- the torso leans against the shift, breathes, and the head looks around.

Channel values are rounded to 4 decimals before writing, so the file does not depend on the
last bits of a platform's ``sin``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._typing import Array
from ..bvh import format_bvh_channels
from ..motion import default_channels
from ..skeleton import Skeleton

SAMPLE_PATH = Path(__file__).resolve().parent / "samples" / "wave.bvh"
FPS = 30
SECONDS = 4.0
HIP_HEIGHT = 16.5
THIGH, SHIN = 7.6, 7.4  # the straight leg, hip to ankle: L = THIGH + SHIN

# (name, parent, offset): parents before children, in BVH (depth-first) order.
JOINTS: list[tuple[str, str | None, tuple[float, float, float]]] = [
    ("Hips", None, (0.0, 0.0, 0.0)),
    ("LeftUpLeg", "Hips", (1.7, -0.8, 0.0)),
    ("LeftLeg", "LeftUpLeg", (0.0, -THIGH, 0.0)),
    ("LeftFoot", "LeftLeg", (0.0, -SHIN, 0.0)),
    ("LeftFoot_end", "LeftFoot", (0.0, -0.7, 2.4)),
    ("RightUpLeg", "Hips", (-1.7, -0.8, 0.0)),
    ("RightLeg", "RightUpLeg", (0.0, -THIGH, 0.0)),
    ("RightFoot", "RightLeg", (0.0, -SHIN, 0.0)),
    ("RightFoot_end", "RightFoot", (0.0, -0.7, 2.4)),
    ("Spine", "Hips", (0.0, 2.0, 0.0)),
    ("Chest", "Spine", (0.0, 3.0, 0.0)),
    ("Neck", "Chest", (0.0, 3.5, 0.0)),
    ("Head", "Neck", (0.0, 1.5, 0.0)),
    ("Head_end", "Head", (0.0, 3.0, 0.0)),
    ("LeftShoulder", "Chest", (0.6, 3.0, 0.0)),
    ("LeftArm", "LeftShoulder", (2.6, 0.0, 0.0)),
    ("LeftForeArm", "LeftArm", (4.8, 0.0, 0.0)),
    ("LeftHand", "LeftForeArm", (4.4, 0.0, 0.0)),
    ("LeftHand_end", "LeftHand", (1.6, 0.0, 0.0)),
    ("RightShoulder", "Chest", (-0.6, 3.0, 0.0)),
    ("RightArm", "RightShoulder", (-2.6, 0.0, 0.0)),
    ("RightForeArm", "RightArm", (-4.8, 0.0, 0.0)),
    ("RightHand", "RightForeArm", (-4.4, 0.0, 0.0)),
    ("RightHand_end", "RightHand", (-1.6, 0.0, 0.0)),
]


def wave_skeleton() -> Skeleton:
    """The sample's skeleton (24 joints including 5 End Sites)."""
    names = [name for name, _, _ in JOINTS]
    parents = [-1 if parent is None else names.index(parent) for _, parent, _ in JOINTS]
    return Skeleton(names, parents, np.array([offset for _, _, offset in JOINTS]))


def wave_channel_values(n_frames: int = round(SECONDS * FPS)) -> np.ndarray:
    """Channel values (n_frames, 60) in file order: root position, then per joint Z, Y, X
    rotation in degrees; frame ``n`` is at time ``n / FPS``."""
    t = np.arange(n_frames) / FPS
    w0 = 2 * np.pi / SECONDS
    wave = 6 * w0  # 1.5 Hz
    shift = 0.5 * np.sin(w0 * t)
    leg = THIGH + SHIN
    tilt = -np.arcsin(shift / leg)
    zeros = np.zeros_like(t)

    def zyx(z: Array = zeros, y: Array = zeros, x: Array = zeros) -> list[Array]:
        return [z, y, x]

    tilt_deg = np.degrees(tilt)
    rotations = {
        "Hips": zyx(),
        "LeftUpLeg": zyx(z=tilt_deg),
        "LeftLeg": zyx(),
        "LeftFoot": zyx(z=-tilt_deg),
        "RightUpLeg": zyx(z=tilt_deg),
        "RightLeg": zyx(),
        "RightFoot": zyx(z=-tilt_deg),
        "Spine": zyx(z=-1.5 * np.sin(w0 * t)),
        "Chest": zyx(x=1.0 * np.sin(2 * w0 * t)),
        "Neck": zyx(x=-0.5 * np.sin(2 * w0 * t)),
        "Head": zyx(y=10.0 * np.sin(w0 * t), x=3.0 * np.sin(2 * w0 * t + 0.5)),
        "LeftShoulder": zyx(),
        "LeftArm": zyx(z=-75.0 + 2.0 * np.sin(w0 * t), y=-5.0 + zeros),
        "LeftForeArm": zyx(y=-15.0 + zeros),
        "LeftHand": zyx(),
        "RightShoulder": zyx(z=-8.0 + zeros),
        "RightArm": zyx(z=-60.0 + 3.0 * np.sin(wave * t), y=15.0 + zeros),
        "RightForeArm": zyx(z=-28.0 + 22.0 * np.sin(wave * t)),
        "RightHand": zyx(z=10.0 * np.sin(wave * t - 0.6)),
    }
    root_position = [shift, HIP_HEIGHT - leg * (1 - np.cos(tilt)), zeros]
    columns = root_position + [
        angle for name, _, _ in JOINTS if not name.endswith("_end") for angle in rotations[name]
    ]
    # Rounded, and -0.0 turned into 0.0, so that the text is the same on every platform.
    return np.round(np.stack(columns, axis=1), 4) + 0.0


def wave_bvh_text() -> str:
    """The exact text of ``samples/wave.bvh``."""
    skeleton = wave_skeleton()
    return format_bvh_channels(
        skeleton, default_channels(skeleton), wave_channel_values(), 1.0 / FPS, fmt="%.4f"
    )


def main() -> None:
    SAMPLE_PATH.parent.mkdir(parents=True, exist_ok=True)
    SAMPLE_PATH.write_text(wave_bvh_text(), encoding="utf-8", newline="\n")
    print(f"wrote {SAMPLE_PATH} ({SAMPLE_PATH.stat().st_size} bytes)")


if __name__ == "__main__":
    main()
