#!/usr/bin/env python3
"""Times ROSS and filterpy on the problems `cargo xtask bench` times edgekf on, and writes the
figures as one JSON object to the file given as the argument (progress on stderr; ROSS's
imports print to stdout).

    cargo xtask bench            # creates target/bench/venv from requirements.txt, runs this
    python peers.py out.json     # by hand, from an empty directory

The problems (the same in `host-sim/examples/speed.rs`):
* the paper rotor (`host-sim/configs/rotor_paper.toml`, built as in
  `tools/fixtures/gen_ross.py`): its time response from rest to the two unbalance forces at
  87.96 rad/s, 4 s and 40 s at 1 kHz, through ROSS's default `lsim`, which interpolates the force
  linearly between samples; the same 4 s at a 10x finer step, to which the 1 kHz run converges;
  the modal analysis at 87.96 rad/s (every mode, dense); the Campbell diagram, 6 frequencies at
  51 speeds from 0 to 1000 rad/s;
* one Kalman predict + update with 4 states and 4 measurements, and one unscented predict +
  update with 14 states and 4 measurements (Merwe points; f(x) = A x - 0.01 x^3,
  h(x) = C x + 0.05 (C x)^2), on random dense models.

Times are compute only (the import, and ROSS's model assembly, are timed apart) and are the
best of a few repetitions. Run from an empty directory (see gen_ross.py: ROSS imports `ccp`).
"""

import json
import math
import os
import sys
import time

T0 = time.perf_counter()
import numpy as np  # noqa: E402
import scipy  # noqa: E402
import ross as rs  # noqa: E402
import filterpy  # noqa: E402
from filterpy.kalman import KalmanFilter, MerweScaledSigmaPoints, UnscentedKalmanFilter  # noqa: E402

IMPORT_S = time.perf_counter() - T0
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "fixtures"))
import gen_ross  # noqa: E402

SPEED = gen_ross.SPEED
RATE = 1000.0
RESPONSE_NODES = (12, 23)


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def best(f, repeat):
    out, times = None, []
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return min(times), out


def step_time(f, z, n):
    """Seconds per predict + update of filter `f` with measurement `z`, best of 3 runs of `n`."""

    def steps():
        for _ in range(n):
            f.predict()
            f.update(z)

    return best(steps, 3)[0] / n


def forces(rotor, t):
    """The unbalance forces m e w^2 (cos, sin)(w t + phase) at their nodes, (len(t), ndof)."""
    f = np.zeros((len(t), rotor.ndof))
    for node, me, phase in gen_ross.UNBALANCE:
        arg = SPEED * t + math.radians(phase)
        f[:, rotor.number_dof * node] = me * SPEED**2 * np.cos(arg)
        f[:, rotor.number_dof * node + 1] = me * SPEED**2 * np.sin(arg)
    return f


def response(rotor, duration, rate):
    t = np.arange(int(round(duration * rate))) / rate
    f = forces(rotor, t)
    _, yout, _ = rotor.time_response(SPEED, f, t)
    cols = [rotor.number_dof * n + d for n in RESPONSE_NODES for d in (0, 1)]
    return yout[:, cols]


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: peers.py OUT.json")
    log(f"imports {IMPORT_S:.1f} s")
    t = time.perf_counter()
    rotor, _ = gen_ross.build()
    build_s = time.perf_counter() - t
    out = dict(
        versions=dict(python=sys.version.split()[0], ross=rs.__version__, filterpy=filterpy.__version__,
                      numpy=np.__version__, scipy=scipy.__version__),
        import_s=IMPORT_S,
        rotor_build_s=build_s,
    )
    log("time response 4 s, 40 s, and 4 s at 10 kHz")
    out["response_4s_s"], r4 = best(lambda: response(rotor, 4.0, RATE), 3)
    out["response_40s_s"], _ = best(lambda: response(rotor, 40.0, RATE), 1)
    fine = response(rotor, 4.0, 10 * RATE)[::10]
    out["response_4s_fine_vs_1khz"] = float(np.sqrt(np.mean((r4 - fine) ** 2)) / np.sqrt(np.mean(fine**2)))
    # The disk nodes' x, y at 1 kHz, for edgekf to compare against.
    out["response_4s_disks"] = r4.tolist()
    out["response_4s_fine_disks"] = fine.tolist()
    log("modal and Campbell")
    # ROSS caches `run_modal` by its arguments: every repetition at a speed of its own (1e-9 off).
    shift = iter(range(100))
    modal = lambda: rotor.run_modal(speed=SPEED + 1e-9 * next(shift), num_modes=4 * rotor.ndof, sparse=False)
    out["modal_s"], _ = best(modal, 5)
    speeds = np.linspace(0.0, 1000.0, 51)
    out["campbell_s"], _ = best(lambda: rotor.run_campbell(speeds + 1e-9 * next(shift), frequencies=6), 2)

    log("filterpy steps")
    rng = np.random.default_rng(7)
    kf = KalmanFilter(dim_x=4, dim_z=4)
    kf.F = np.eye(4) + 0.01 * rng.standard_normal((4, 4))
    kf.H = rng.standard_normal((4, 4))
    kf.Q, kf.R, kf.P = np.eye(4) * 1e-3, np.eye(4), np.eye(4)
    out["kf_step_s"] = step_time(kf, rng.standard_normal(4), 20000)
    a = np.eye(14) + 0.01 * rng.standard_normal((14, 14))
    c = rng.standard_normal((4, 14))
    ukf = UnscentedKalmanFilter(dim_x=14, dim_z=4, dt=1.0, hx=lambda x: (lambda y: y + 0.05 * y * y)(c @ x),
                                fx=lambda x, dt: a @ x - 0.01 * x**3,
                                points=MerweScaledSigmaPoints(14, alpha=0.5, beta=2.0, kappa=0.0))
    ukf.Q, ukf.R = np.eye(14) * 1e-3, np.eye(4)
    out["ukf_step_s"] = step_time(ukf, rng.standard_normal(4), 2000)
    tmp = sys.argv[1] + ".tmp"
    with open(tmp, "w") as f:
        json.dump(out, f)
    os.replace(tmp, sys.argv[1])


if __name__ == "__main__":
    main()
