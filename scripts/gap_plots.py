#!/usr/bin/env python3
"""Plots of a diagnose_gap output folder: spectra and Allan curves (real vs sim vs sim+effect,
withheld part), a gap heat map (axis x band, z of the withheld part before the verdict), drift
curves (block means of the whole recording against the ensemble's range), the heave spectra of
the motion stage (motion.png, when the motion differs) and, with a truth, the residual real
minus the ideal IMU of the truth against the simulated runs' own (truth.png).

    /usr/bin/python3 scripts/gap_plots.py --dir OUT [--title TEXT]
"""
import argparse
import csv
import math
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

CH = ["ax", "ay", "az", "gx", "gy", "gz"]


def save(fig, path):
    """Writes the figure under a temporary name, renamed when complete (as the tools' files)."""
    temporary = "%s.partial-%d.png" % (path[:-4], os.getpid())
    try:
        fig.savefig(temporary, dpi=72)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def curves(rows, xkey):
    out = defaultdict(lambda: defaultdict(list))
    for r in rows:
        for k, v in r.items():
            if k != "channel":
                try:
                    out[r["channel"]][k].append(float(v))
                except ValueError:
                    out[r["channel"]][k].append(float("nan"))
    return out


def grid(title):
    fig, axes = plt.subplots(2, 3, figsize=(11, 6.2), sharex=True)
    fig.suptitle(title, fontsize=9)
    return fig, axes.ravel()


def block_plot(d, name, title):
    """Block means of NAME.csv: real against the ensemble's range (and the verdict's median)."""
    dr = curves(read(os.path.join(d, name + ".csv")), "t")
    fig, axes = grid(title)
    for i, c in enumerate(CH):
        ax = axes[i]
        p = dr[c]
        ax.fill_between(p["t"], p["sim_lo"], p["sim_hi"], color="tab:blue", alpha=0.25, label="sim range")
        ax.plot(p["t"], p["sim_med"], color="tab:blue", lw=0.8)
        if "sim_effect_med" in p:
            ax.plot(p["t"], p["sim_effect_med"], color="tab:red", ls="--", lw=0.8, label="sim + verdict")
        ax.plot(p["t"], p["real"], color="k", lw=0.9, label="real")
        ax.set_title(c, fontsize=8)
        ax.tick_params(labelsize=7)
        if i >= 3:
            ax.set_xlabel("t [s]", fontsize=7)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    save(fig, os.path.join(d, name + ".png"))
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dir", required=True)
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    d = a.dir

    psd = curves(read(os.path.join(d, "psd.csv")), "f")
    fig, axes = grid("PSD of the withheld part: " + a.title)
    for i, c in enumerate(CH):
        ax = axes[i]
        p = psd[c]
        ax.loglog(p["f"], p["real"], lw=0.7, color="k", label="real")
        ax.loglog(p["f"], p["sim"], lw=0.7, color="tab:blue", label="sim (median)")
        ax.loglog(p["f"], p["sim_effect"], lw=0.7, color="tab:red", ls="--", label="sim + verdict")
        ax.set_title(c, fontsize=8)
        ax.tick_params(labelsize=7)
        if i >= 3:
            ax.set_xlabel("Hz", fontsize=7)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    save(fig, os.path.join(d, "spectra.png"))
    plt.close(fig)

    al = curves(read(os.path.join(d, "allan.csv")), "tau")
    fig, axes = grid("Allan deviation of the withheld part: " + a.title)
    for i, c in enumerate(CH):
        ax = axes[i]
        p = al[c]
        ax.loglog(p["tau"], p["real"], "o-", ms=3, lw=0.8, color="k", label="real")
        ax.loglog(p["tau"], p["sim"], "s-", ms=3, lw=0.8, color="tab:blue", label="sim (median)")
        ax.loglog(p["tau"], p["sim_effect"], "^--", ms=3, lw=0.8, color="tab:red", label="sim + verdict")
        ax.set_title(c, fontsize=8)
        ax.tick_params(labelsize=7)
        if i >= 3:
            ax.set_xlabel("tau [s]", fontsize=7)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    save(fig, os.path.join(d, "allan.png"))
    plt.close(fig)

    if os.path.exists(os.path.join(d, "motion.csv")):
        m = curves([dict(r, channel="heave") for r in read(os.path.join(d, "motion.csv"))], "f")["heave"]
        fig, ax = plt.subplots(figsize=(7, 3.6))
        ax.semilogy(m["f"], m["real"], color="k", lw=1.0, label="recording")
        ax.semilogy(m["f"], m["given"], color="tab:blue", lw=0.9, label="scenario as given (ensemble mean)")
        ax.semilogy(m["f"], m["fitted"], color="tab:red", ls="--", lw=0.9, label="motion fitted (ensemble mean)")
        ax.set_xlabel("Hz", fontsize=8)
        ax.set_ylabel("heave [m^2/Hz]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_title("Heave spectrum, the motion stage's wave band: " + a.title, fontsize=8)
        ax.legend(fontsize=7)
        fig.tight_layout()
        save(fig, os.path.join(d, "motion.png"))
        plt.close(fig)

    block_plot(d, "drift", "Block means (drift), whole recording: " + a.title)
    if os.path.exists(os.path.join(d, "truth.csv")):
        block_plot(d, "truth", "Real minus the ideal IMU of its truth (block means) vs the simulated runs' own: " + a.title)

    feats = read(os.path.join(d, "features.csv"))
    bands = []
    for r in feats:
        if r["quantity"] == "psd" and r["range"] not in bands:
            bands.append(r["range"])
    z = [[float("nan")] * len(bands) for _ in CH]
    left_out = []  # (band, channel) cells the motion stage left out of the sensor diagnosis
    for r in feats:
        if r["quantity"] == "psd" and r["channel"] in CH:
            z[CH.index(r["channel"])][bands.index(r["range"])] = float(r["z_before"])
            if r.get("left_out") == "1":
                left_out.append((bands.index(r["range"]), CH.index(r["channel"])))
    fig, ax = plt.subplots(figsize=(11, 3.2))
    vals = [[max(-30, min(30, v)) if not math.isnan(v) else 0 for v in row] for row in z]
    im = ax.imshow(vals, aspect="auto", cmap="RdBu_r", vmin=-30, vmax=30)
    ax.set_yticks(range(len(CH)))
    ax.set_yticklabels(CH, fontsize=7)
    ax.set_xticks(range(len(bands)))
    ax.set_xticklabels([b.replace(" Hz", "") for b in bands], rotation=90, fontsize=6)
    ax.set_xlabel("band [Hz]", fontsize=7)
    title = "gap heat map: z of log PSD per band, withheld part, base ensemble (clipped +-30)"
    if left_out:
        ax.scatter([c[0] for c in left_out], [c[1] for c in left_out], marker="x", color="0.4", s=18, lw=0.8)
        title += "; x: the motion's, left out"
    ax.set_title(title + ": " + a.title, fontsize=8)
    fig.colorbar(im, ax=ax, fraction=0.02)
    fig.tight_layout()
    save(fig, os.path.join(d, "heatmap.png"))
    plt.close(fig)


if __name__ == "__main__":
    main()
