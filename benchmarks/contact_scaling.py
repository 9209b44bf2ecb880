#!/usr/bin/env python3
"""Cost of liemid's contact step against the number of resting bodies (issue 45).

N spheres (radius 0.05 m, 1 kg, friction 0.5) rest on a floor in a square grid with 0.02 m
between neighbours (one contact each, none between spheres), for N = 1,000 and 10,000;
`liemid multibody --method liemid` at h = 1e-3 for 20 steps. Printed: the time per step
(`stepping_seconds / steps` of the JSON summary), per body, the ratio between the two sizes
(linear cost: about 10; quadratic: about 100), and the deepest penetration. No peer: the
question is the scaling of liemid alone.

Run:  python benchmarks/contact_scaling.py      (LIEMID_BIN to point at the binary)
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from liemid_binary import require_liemid  # noqa: E402

RADIUS, GAP, STEPS = 0.05, 0.02, 20


def scene(n: int) -> str:
    """The MJCF of `n` spheres resting on a floor in a square grid."""
    side = math.ceil(math.sqrt(n))
    pitch = 2 * RADIUS + GAP
    bodies = []
    for k in range(n):
        x, y = (k % side) * pitch, (k // side) * pitch
        bodies.append(f'<body name="s{k}" pos="{x:.4f} {y:.4f} {RADIUS}"><freejoint/>'
                      f'<geom type="sphere" size="{RADIUS}" mass="1" friction="0.5"/></body>')
    return ('<mujoco model="resting spheres"><worldbody><geom name="floor" type="plane" size="0 0 1"/>'
            + "".join(bodies) + "</worldbody></mujoco>")


def main() -> None:
    liemid = require_liemid("contact_scaling")
    per_step = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1000, 10000):
            path = Path(tmp) / f"spheres_{n}.xml"
            path.write_text(scene(n))
            done = subprocess.run([liemid, "multibody", str(path), "--step", "1e-3", "--t-end", str(STEPS * 1e-3),
                                   "--max-steps", str(STEPS), "--json", "-"], capture_output=True, text=True)
            if done.returncode != 0:
                print(f"N = {n}: liemid failed: {done.stderr.strip()}")
                return
            s = json.loads(done.stdout)
            per_step[n] = s["stepping_seconds"] / s["steps"]
            c = s["contacts"]
            print(f"N = {n:6d}: {per_step[n] * 1e3:8.2f} ms per step, {per_step[n] / n * 1e6:6.2f} us per body, "
                  f"most points {c['most_points']}, deepest penetration {c['deepest_penetration']:.1e} m")
    print(f"ratio 10,000 / 1,000: {per_step[10000] / per_step[1000]:.1f} (linear: about 10)")


if __name__ == "__main__":
    main()
