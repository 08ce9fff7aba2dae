#!/usr/bin/env python3
"""Drift with and without compensation, from a recording of the compensator's outputs.

Usage: plot_drift.py --input INPUT.bag --output OUTPUT.bag --png PLOT.png [--title TEXT]

INPUT.bag: the replayed bag (imu/data and, from the simulator, ground_truth/*).
OUTPUT.bag: what launch/record.launch recorded (odometry/filtered, odometry/wave, ...).
Prints, per axis, the final position of plain double integration, of odometry/filtered and of
filtered + wave, against the truth when the input has it; writes a plot.
"""
import argparse
import sys

import numpy as np
import rosbag

G = 9.80665


def quat_rotate(q, v):
    """Rotates vectors v (N x 3) by unit quaternions q (N x 4, x y z w)."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    u = np.stack([x, y, z], axis=1)
    t = 2.0 * np.cross(u, v)
    return v + w[:, None] * t + np.cross(u, t)


def read_odometry(bag, topic):
    t, p = [], []
    for _, msg, _ in bag.read_messages(topics=[topic]):
        t.append(msg.header.stamp.to_sec())
        pos = msg.pose.pose.position
        p.append((pos.x, pos.y, pos.z))
    return np.array(t), np.array(p).reshape(-1, 3)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--input", required=True)
    parser.add_argument("--output", required=True)
    parser.add_argument("--png", required=True)
    parser.add_argument("--title", default="")
    args = parser.parse_args()

    with rosbag.Bag(args.input) as bag:
        stamps, force, quats = [], [], []
        for _, msg, _ in bag.read_messages(topics=["imu/data"]):
            stamps.append(msg.header.stamp.to_sec())
            a = msg.linear_acceleration
            o = msg.orientation
            force.append((a.x, a.y, a.z))
            quats.append((o.x, o.y, o.z, o.w))
        if not stamps:
            sys.exit("plot_drift: no imu/data in %s" % args.input)
        truth_t, truth_p = read_odometry(bag, "ground_truth/odometry")
        slow_t, slow_p = read_odometry(bag, "ground_truth/slow")
    stamps = np.array(stamps)
    level = quat_rotate(np.array(quats), np.array(force)) - np.array([0.0, 0.0, G])
    dt = np.diff(stamps, prepend=stamps[0])
    raw_v = np.cumsum(level * dt[:, None], axis=0)
    raw_p = np.cumsum(raw_v * dt[:, None], axis=0)

    with rosbag.Bag(args.output) as bag:
        filt_t, filt_p = read_odometry(bag, "odometry/filtered")
        wave_t, wave_p = read_odometry(bag, "odometry/wave")
    if len(filt_t) == 0:
        sys.exit("plot_drift: no odometry/filtered in %s: did the compensator run?" % args.output)

    t0 = stamps[0]
    have_truth = len(truth_t) > 0
    if have_truth:
        origin = slow_p[0] if len(slow_t) else truth_p[0]
        truth_rel = truth_p - origin
        slow_rel = slow_p - origin if len(slow_t) else None
    n = min(len(filt_t), len(wave_t))
    total = filt_p[:n] + wave_p[:n]

    print("after %.1f s (axis: raw double integration | odometry/filtered | filtered + wave%s)"
          % (stamps[-1] - t0, " | truth" if have_truth else ""))
    for i, name in enumerate("xyz"):
        line = "  %s: %9.3f m | %8.4f m | %8.4f m" % (name, raw_p[-1, i], filt_p[-1, i], total[-1, i])
        if have_truth:
            line += " | %8.4f m" % truth_rel[-1, i]
        print(line)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(14, 7), sharex=True)
    for i, name in enumerate("xyz"):
        top, bottom = axes[0, i], axes[1, i]
        top.plot(stamps - t0, raw_p[:, i], color="tab:red", label="double integration (no compensation)")
        top.plot(filt_t - t0, filt_p[:, i], color="tab:blue", label="odometry/filtered")
        top.set_title("%s axis: drift" % name)
        top.set_ylabel("position [m]")
        top.grid(True, alpha=0.3)
        bottom.plot(filt_t[:n] - t0, total[:, i], color="tab:blue", label="filtered + wave")
        if have_truth:
            bottom.plot(truth_t - t0, truth_rel[:, i], color="k", lw=0.8, ls="--", label="truth")
        bottom.set_title("%s axis: compensated motion (zoom)" % name)
        bottom.set_xlabel("time [s]")
        bottom.set_ylabel("position [m]")
        bottom.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="upper left", fontsize=8)
    axes[1, 0].legend(loc="upper left", fontsize=8)
    fig.suptitle(args.title or "periodic_bias_compensation: drift with and without compensation")
    fig.tight_layout()
    fig.savefig(args.png, dpi=90)
    print("plot: %s" % args.png)


if __name__ == "__main__":
    main()
