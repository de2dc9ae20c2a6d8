#!/usr/bin/env python3
# Compares groups of `rendulic run` results made from independent packings (seeds) with one
# setting changed between groups, as docs/accuracy.md "The protocol's time step" did: per group
# the mean and its standard error over the seeds of the isotropic branch (P* and coordination at
# a few volume fractions), the undrained path's steady state (q/P = sqrt(3 J2)/P,
# coordination and fabric deviator averaged over the last 37.5 % of eps_dev, dem.md "Paths"),
# the states' P*, coordination and linear-response envelope extent, and the stages' wall times
# (frictional packings: also the path's sliding fraction; a loading to a pressure: its end);
# then each group against the first: the relative difference of the means and how many
# standard errors it is. A single packing of 1000 particles scatters by several per cent in its
# steady state, so a difference means something only in standard errors.
#
#   python3 bench/protocol_spread.py "0.02=out/dt0.02_s*" "0.1=out/dt0.1_s*"
#
# Each argument is LABEL=GLOB over run directories (each with results.h5). Needs h5py, numpy.
import glob
import sys

import h5py
import numpy as np

NU = (0.66, 0.70, 0.76, 0.82)
STEADY_FROM = 0.625  # of eps_dev_max (dem::kSteadyStateFrom)


def metrics(path):
    out = {}
    with h5py.File(path, "r") as f:
        if "isotropic" in f:
            iso = f["isotropic"]
            nu = iso["volume_fraction"][()]
            for target in NU:
                if not nu.min() - 0.005 <= target <= nu.max() + 0.005:
                    continue  # a loading to a pressure may end below these volume fractions
                i = int(np.argmin(abs(nu - target)))
                out[f"isotropic P* at nu {target}"] = iso["pressure_star"][i]
                out[f"isotropic C at nu {target}"] = iso["coordination"][i]
            out["isotropic end nu"] = nu[-1]
            out["isotropic end P*"] = iso["pressure_star"][-1]
            out["isotropic end C"] = iso["coordination"][-1]
        if "path" in f:
            p = f["path"]
            e = np.abs(p["eps_dev"][()])
            s = p["stress"][()]
            P = np.trace(s, axis1=1, axis2=2) / 3
            dev = s - P[:, None, None] * np.eye(3)
            q = np.sqrt(1.5 * np.einsum("nij,nij->n", dev, dev)) / P
            w = e >= STEADY_FROM * e.max()
            F = p["fabric"][()]
            out["path steady q/P (sqrt(3 J2)/P)"] = q[w].mean()
            out["path steady C"] = p["coordination"][()][w].mean()
            out["path steady fabric F_xx - F_lateral"] = (
                F[:, 0, 0] - 0.5 * (F[:, 1, 1] + F[:, 2, 2]))[w].mean()
            out["path p_end / p0"] = P[-1] / P[0]
            if "sliding_fraction" in p:  # frictional packings
                out["path steady sliding fraction"] = p["sliding_fraction"][()][w].mean()
        for label in f["states"] if "states" in f else []:
            g = f["states"][label]
            out[f"state {label} P*"] = g.attrs["pressure_star"]
            out[f"state {label} C"] = g.attrs["coordination"]
            lr = "envelopes/linear_response_5e-05/d_stress"
            if lr in g:
                n = np.sqrt(np.einsum("nij,nij->n", g[lr][()], g[lr][()]))
                out[f"state {label} linear response max |d_sigma|"] = n.max()
                out[f"state {label} linear response min |d_sigma|"] = n.min()
        for stage, t in f["timings"].attrs.items():
            out[f"wall s {stage}"] = float(t)
    return out


def main(args):
    groups = []
    for a in args:
        label, pattern = a.split("=", 1)
        runs = [metrics(d + "/results.h5") for d in sorted(glob.glob(pattern))
                if glob.glob(d + "/results.h5")]
        if not runs:
            sys.exit(f"protocol_spread: no results.h5 under {pattern}")
        groups.append((label, runs))
    keys = [k for k in groups[0][1][0] if all(k in r for _, runs in groups for r in runs)]
    head = [f"{label} (n = {len(runs)})" for label, runs in groups]
    head += [f"{label} vs {groups[0][0]}" for label, _ in groups[1:]]
    print("| quantity | " + " | ".join(head) + " |")
    print("|---" * (len(head) + 1) + "|")
    for k in keys:
        stats = []
        for _, runs in groups:
            v = np.array([r[k] for r in runs])
            se = v.std(ddof=1) / np.sqrt(len(v)) if len(v) > 1 else float("nan")
            stats.append((v.mean(), se))
        row = [k] + [f"{m:.4g} +- {se:.2g}" for m, se in stats]
        m0, s0 = stats[0]
        for m, se in stats[1:]:
            if k.startswith("wall s"):
                row.append(f"{m / m0:.2f}x")
            else:
                row.append(f"{100 * (m - m0) / abs(m0):+.2f} % ({(m - m0) / np.hypot(s0, se):+.1f} se)")
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: protocol_spread.py LABEL=GLOB [LABEL=GLOB ...]")
    main(sys.argv[1:])
