#!/usr/bin/env python3
"""Plots a simulate_imu CSV: sensor error (measured minus ideal IMU of the truth), its
one-sided PSD, and the truth split into slow and wave motion.

Usage: sim_inspect.py --csv RUN.csv --png RUN.png
       (RUN.csv from `simulate_imu --scenario F.yaml --csv RUN.csv`)
Needs Debian's python3-numpy and python3-matplotlib (run with /usr/bin/python3).
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

G = 9.80665


def rotate_inverse(qw, qx, qy, qz, v):
    """Rotates ENU vectors v (N x 3) into the body frame by the conjugates of unit quaternions."""
    u = np.stack([-qx, -qy, -qz], axis=1)
    t = 2.0 * np.cross(u, v)
    return v + qw[:, None] * t + np.cross(u, t)


def psd(x, fs, segment=1024):
    """One-sided Welch PSD with a Hann window [unit^2/Hz]."""
    segment = min(segment, len(x))
    w = np.hanning(segment)
    step = segment // 2
    spectra = [np.abs(np.fft.rfft(w * (x[i:i + segment] - np.mean(x[i:i + segment])))) ** 2
               for i in range(0, len(x) - segment + 1, step)]
    scale = 2.0 / (fs * np.sum(w ** 2))
    return np.fft.rfftfreq(segment, 1.0 / fs), scale * np.mean(spectra, axis=0)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--csv", required=True)
    parser.add_argument("--png", required=True)
    args = parser.parse_args()

    d = np.genfromtxt(args.csv, delimiter=",", names=True)
    kept = d["dropped"] == 0
    t = d["t"] - d["t"][0]
    fs = 1.0 / np.median(np.diff(t))
    acc = np.stack([d["acc_x"], d["acc_y"], d["acc_z"]], axis=1) + np.array([0.0, 0.0, G])
    ideal = rotate_inverse(d["att_w"], d["att_x"], d["att_y"], d["att_z"], acc)
    error = np.stack([d["ax"], d["ay"], d["az"]], axis=1) - ideal

    fig, axes = plt.subplots(3, 1, figsize=(10, 10))
    for i, name in enumerate("xyz"):
        axes[0].plot(t[kept], error[kept, i], lw=0.5, label=f"accel {name}")
        f, p = psd(error[kept, i], fs)
        axes[1].loglog(f[1:], np.sqrt(p[1:]), lw=0.7, label=f"accel {name}")
    axes[0].set_xlabel("time [s]")
    axes[0].set_ylabel("measured - ideal [m/s^2]")
    axes[0].legend()
    axes[1].set_xlabel("frequency [Hz]")
    axes[1].set_ylabel("error ASD, one-sided [m/s^2/sqrt(Hz)]")
    axes[1].legend()
    for name, style in (("slow_p", "-"), ("wave_p", "--")):
        for axis in "xyz":
            axes[2].plot(t, d[f"{name}{axis}"], style, lw=0.7, label=f"{name}{axis}")
    axes[2].set_xlabel("time [s]")
    axes[2].set_ylabel("truth position [m]")
    axes[2].legend(ncol=2, fontsize="small")
    fig.tight_layout()
    fig.savefig(args.png, dpi=90)
    print(f"{args.csv}: {len(t)} samples at {fs:.3f} Hz, {np.count_nonzero(~kept)} dropped; "
          f"mean error {np.mean(error[kept], axis=0)} m/s^2 -> {args.png}")


if __name__ == "__main__":
    main()
