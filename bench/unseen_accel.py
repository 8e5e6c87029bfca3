"""The acceleration a recorded flight's vehicles made that the guidance did not command.

``analysis.disturbance_accel`` is the steady push per vehicle that the shape's
weakest mode must hold (docs/analysis.md, "How firmly the shape is held"). This
reads a ``.tlog`` of a flight (``gcs fly --record`` or the GCS's recording of real
vehicles) and, over each window of ``--window`` seconds in formation flight, fits
each vehicle's mean acceleration from its positions (the simulator's truth where
recorded, else its telemetry), subtracts the mean commanded acceleration, and
keeps the part that deforms the shape (the team's common translation and turn
removed). It prints the largest per vehicle and the median over the windows:

    python bench/unseen_accel.py FLIGHT.tlog [--window 8]

Measured on the simulator, calm air, the paper flight (seed 1 for the square,
seed 2 for the ring of twelve), windows of 4 / 8 / 16 s:
square max 0.044 / 0.064 / 0.069, median 0.014 / 0.010 / 0.012 m/s^2; the ring,
whose uneven rope pulls grow as it deforms, max 0.46 / 0.27 / 0.13, median
0.22 / 0.09 / 0.07 m/s^2.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from gcs.flightlog import FlightLog, LogError
from gcs.loop import Phase


def positions(log: FlightLog) -> np.ndarray:
    """(ticks, n, 2) horizontal positions at the guidance ticks: truth, else telemetry."""
    truth = log.per_vehicle("veh_true", 3)[..., :2]
    if np.isfinite(truth).any() or log.team is None:
        return truth
    out = np.full((len(log.tick_t), len(log.team["ids"]), 2), np.nan)
    for i, vid in enumerate(log.team["ids"]):
        track = log.tracks.get(vid)
        if track is not None and len(track.t) > 1:
            for axis in range(2):
                out[:, i, axis] = np.interp(log.tick_t, track.t, track.p_ned[:, axis],
                                            left=np.nan, right=np.nan)
    return out


def unseen(log: FlightLog, window: float) -> np.ndarray:
    """The largest per-vehicle unseen acceleration (deforming part) of each window in
    formation flight, m/s^2."""
    t, p = log.tick_t, positions(log)
    n = p.shape[1]
    cmd = log.per_vehicle("acc_cmd", 2)
    flying = log.phase == int(Phase.FORMATION)
    k = max(round(window / float(np.median(np.diff(t)))), 3)
    out = []
    for s in range(len(t) - k):
        span = slice(s, s + k + 1)
        if not (flying[span].all() and np.isfinite(p[span]).all()
                and np.isfinite(cmd[span]).all()):
            continue
        tt = t[span] - t[s]
        fit = np.vstack([np.ones_like(tt), tt, 0.5 * tt ** 2]).T
        coef = np.linalg.lstsq(fit, p[span].reshape(len(tt), -1), rcond=None)[0]
        residual = (coef[2].reshape(n, 2) - cmd[span][:-1].mean(axis=0)).ravel()
        c = p[s + k // 2] - p[s + k // 2].mean(axis=0)  # the team's turn about its centroid
        rigid = np.array([np.tile([1.0, 0.0], n), np.tile([0.0, 1.0], n),
                          np.column_stack([-c[:, 1], c[:, 0]]).ravel()]).T
        q, _ = np.linalg.qr(rigid)
        deforming = residual - q @ (q.T @ residual)
        out.append(float(np.linalg.norm(deforming.reshape(n, 2), axis=1).max()))
    return np.array(out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", help="a recorded flight (.tlog)")
    parser.add_argument("--window", type=float, default=8.0, help="window, s (default 8)")
    args = parser.parse_args()
    try:
        log = FlightLog.load(args.log)
    except (OSError, LogError) as exc:
        print(f"unseen_accel: {exc}", file=sys.stderr)
        return 1
    found = unseen(log, args.window)
    if not len(found):
        print(f"unseen_accel: {args.log}: no {args.window:g} s of formation flight with "
              f"positions and commands", file=sys.stderr)
        return 1
    print(f"{args.log}: {len(found)} windows of {args.window:g} s in formation: unseen "
          f"acceleration per vehicle max {found.max():.4f}, median {np.median(found):.4f} "
          f"m/s^2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
