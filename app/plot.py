# Figures of a rendulic results file (issue 8; seed paper Figs. 1-7 and the isotropic branch).
# Embedded into the `rendulic` binary at build time and run by `rendulic plot FILE.h5 --out DIR`
# with Debian's python3-matplotlib and python3-h5py. Reads only the names of interfaces.md
# (schema rendulic/1), so it works on any conforming file; a figure whose data is absent is
# skipped with a note, never faked. Writes each figure as PNG and SVG.
import math
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ISO = math.degrees(math.atan(1 / math.sqrt(2)))  # 35.26 deg
SPECIAL = {"I.C.": ISO, "I.E.": ISO + 180, "U.C.": 90.0, "U.E.": 270.0,
           "D.C.": ISO + 90, "D.E.": ISO + 270}
ELASTIC_MAX, PLASTIC_MIN = 1e-4, 1e-3  # physics.md section 5


def save(fig, out, name, written):
    for ext in ("png", "svg"):
        path = os.path.join(out, f"{name}.{ext}")
        fig.savefig(path, dpi=130, bbox_inches="tight")
        written.append(path)
    plt.close(fig)


def attr(obj, name, default=None):
    v = obj.attrs.get(name, default)
    if isinstance(v, bytes):
        v = v.decode()
    return v


def states(f):
    if "states" not in f:
        return []
    out = [(float(attr(g, "eps_dev", 0.0)), label, g) for label, g in f["states"].items()]
    return sorted(out, key=lambda t: -t[0])  # -eps_dev increasing (extension: eps_dev < 0)


def envelopes(state_group, kind):
    """Envelopes of a state that are elastic (amplitude < 1e-4) or plastic (> 1e-3)."""
    if "envelopes" not in state_group:
        return []
    out = []
    for name, g in state_group["envelopes"].items():
        a = float(attr(g, "amplitude", 0.0))
        if (kind == "elastic" and a < ELASTIC_MAX) or (kind == "plastic" and a > PLASTIC_MIN):
            out.append((name, g))
    return out


def fit_curve(fit):
    c = np.asarray(attr(fit, "center", [0, 0]), dtype=float)
    a, b = np.asarray(attr(fit, "semi_axes", [0, 0]), dtype=float)
    inc = attr(fit, "inclination_deg")
    if inc is None or not np.isfinite(inc):
        inc = 0.0
    phi = math.radians(float(inc))
    t = np.linspace(0, 2 * math.pi, 200)
    x = a * np.cos(t) * math.cos(phi) - b * np.sin(t) * math.sin(phi) + c[0]
    y = a * np.cos(t) * math.sin(phi) + b * np.sin(t) * math.cos(phi) + c[1]
    return x, y


def fig_isotropic(f, out, written, notes):
    if "isotropic" not in f:
        notes.append("isotropic branch: no /isotropic")
        return
    g = f["isotropic"]
    nu = g["volume_fraction"][:]
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.6))
    ax[0].plot(nu, g["pressure_star"][:], ".-")
    ax[0].set_xlabel(r"$\nu$")
    ax[0].set_ylabel(r"$P^*$")
    ax[1].plot(nu, g["coordination_nonrattler"][:], ".-", label=r"$C^*$")
    ax[1].plot(nu, g["coordination"][:], ".-", label="$C$")
    ax[1].set_xlabel(r"$\nu$")
    ax[1].legend()
    fig.suptitle("Isotropic branch")
    save(fig, out, "isotropic_branch", written)


def fig1_path(f, out, written, notes):
    if "path" not in f:
        notes.append("Fig. 1: no /path")
        return
    g = f["path"]
    x = -g["eps_dev"][:]
    s, F = g["stress_star"][:], g["fabric"][:]
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    for i, lab in enumerate(("xx", "yy", "zz")):
        ax[0].plot(x, s[:, i, i], label=rf"$\sigma^*_{{{lab}}}$")
        ax[1].plot(x, F[:, i, i], label=f"$F_{{{lab}}}$")
    for eps, label, _ in states(f):
        for a in ax:
            a.axvline(-eps, color="0.8", lw=0.8, zorder=0)
    ax[0].set_xlabel(r"$-\varepsilon_{dev}$")
    ax[1].set_xlabel(r"$-\varepsilon_{dev}$")
    ax[0].legend()
    ax[1].legend()
    ax[0].set_title("(a) stress")
    ax[1].set_title("(b) fabric")
    save(fig, out, "fig1_path", written)


def fig2_strain_circle(out, written):
    fig, ax = plt.subplots(figsize=(4.2, 4.2))
    t = np.linspace(0, 2 * math.pi, 300)
    ax.plot(np.cos(t), np.sin(t), "k-", lw=1)
    for name, deg in SPECIAL.items():
        r = math.radians(deg)
        ax.plot([0, math.cos(r)], [0, math.sin(r)], lw=0.8,
                color="tab:red" if name.startswith("I") else
                "tab:blue" if name.startswith("D") else "tab:green")
        ax.annotate(f"{name} {deg:.2f}°", (1.08 * math.cos(r), 1.08 * math.sin(r)),
                    ha="center", fontsize=7)
    ax.set_aspect("equal")
    ax.set_xlabel(r"$\sqrt{2}\,\delta\varepsilon_{yy}/|\delta\varepsilon|$")
    ax.set_ylabel(r"$\delta\varepsilon_{xx}/|\delta\varepsilon|$")
    ax.set_xlim(-1.5, 1.5)
    ax.set_ylim(-1.5, 1.5)
    ax.set_title("Fig. 2: strain probes in the Rendulic plane")
    save(fig, out, "fig2_strain_circle", written)


def fig_envelopes(f, out, written, notes, number, kind, quantity):
    sts = states(f)
    found = [(eps, label, envelopes(g, kind)) for eps, label, g in sts]
    found = [x for x in found if x[2]]
    if not found:
        notes.append(f"Fig. {number}: no {kind} envelopes")
        return
    n = len(found)
    fig, axes = plt.subplots(1, n, figsize=(3.3 * n, 3.4), squeeze=False)
    key = "stress_star" if quantity == "stress" else "fabric"
    fit_key = "fit_stress" if quantity == "stress" else "fit_fabric"
    for ax, (eps, label, envs) in zip(axes[0], found):
        for name, g in envs:
            if key not in g:
                continue
            r = g[key][:]
            th = g["theta_deg"][:] if "theta_deg" in g else None
            method = attr(g, "method", "?")
            ax.plot(r[:, 0], r[:, 1], ".", ms=4, label=f"{method}")
            if th is not None:
                for deg in SPECIAL.values():
                    i = int(np.argmin(np.abs(((th - deg + 180) % 360) - 180)))
                    if abs(((th[i] - deg + 180) % 360) - 180) < 1e-6:
                        ax.plot(r[i, 0], r[i, 1], "o", mfc="none", color="k", ms=6)
            if fit_key in g:
                x, y = fit_curve(g[fit_key])
                ax.plot(x, y, "-", lw=0.8)
        ax.axhline(0, color="0.85", lw=0.6)
        ax.axvline(0, color="0.85", lw=0.6)
        ax.set_title(rf"$-\varepsilon_{{dev}}$ = {-eps:.3f}", fontsize=9)
        ax.set_xlabel(r"$\sqrt{2}\,\delta " + ("\\sigma^*" if quantity == "stress" else "F") +
                      r"_{yy}$")
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel(r"$\delta " + ("\\sigma^*" if quantity == "stress" else "F") +
                          r"_{xx}$")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"Fig. {number}: {kind} {quantity} response envelopes")
    save(fig, out, f"fig{number}_{kind}_{quantity}", written)


def fig7_trends(f, out, written, notes):
    rows = {"elastic": [], "plastic": []}
    for eps, label, g in states(f):
        for kind in rows:
            for name, e in envelopes(g, kind):
                if attr(e, "method") == "linear_response":
                    continue  # Fig. 7 compares probes; linear response is in Figs. 3-4
                fs, ff = e.get("fit_stress"), e.get("fit_fabric")
                if fs is None:
                    continue
                sa = np.asarray(attr(fs, "semi_axes", [np.nan, np.nan]), dtype=float)
                inc_f = attr(ff, "inclination_deg", np.nan) if ff is not None else np.nan
                rows[kind].append((-eps, attr(fs, "inclination_deg", np.nan), inc_f,
                                   sa[0], sa[1]))
    if not rows["elastic"] and not rows["plastic"]:
        notes.append("Fig. 7: no fitted envelopes")
        return
    fig, ax = plt.subplots(1, 4, figsize=(14, 3.3))
    titles = [r"(a) $\theta_\sigma$ [deg]", r"(b) $\theta_F$ [deg]",
              "(c) major axis / first state", "(d) minor axis / first state"]
    for kind, style in (("elastic", "o"), ("plastic", "s")):
        r = sorted(rows[kind])
        if not r:
            continue
        a = np.array(r, dtype=float)
        mfc = "none" if kind == "elastic" else None
        ax[0].plot(a[:, 0], a[:, 1], style + "-", mfc=mfc, label=kind)
        ax[1].plot(a[:, 0], a[:, 2], style + "-", mfc=mfc, label=kind)
        ax[2].plot(a[:, 0], a[:, 3] / a[0, 3], style + "-", mfc=mfc, label=kind)
        ax[3].plot(a[:, 0], a[:, 4] / a[0, 4] if a[0, 4] else a[:, 4], style + "-", mfc=mfc,
                   label=kind)
    ax[0].axhline(ISO, color="tab:red", lw=0.8)
    ax[1].axhline(ISO, color="tab:red", lw=0.8)
    for a, t in zip(ax, titles):
        a.set_title(t, fontsize=9)
        a.set_xlabel(r"$-\varepsilon_{dev}$")
    ax[0].legend(fontsize=7)
    fig.suptitle("Fig. 7: envelope features along the path")
    save(fig, out, "fig7_features", written)


FACTOR_STYLE = {"dt_factor": ("o", "tab:blue"), "dt_factor_tight": ("o", "tab:cyan"),
                "n_particles": ("s", "tab:green"), "inertial_number": ("^", "tab:orange"),
                "relax": ("D", "tab:purple"), "method": ("*", "tab:red")}
METHOD_MARKER = {"dynamic": "*", "minimisation": "P", "linear_response": "X"}
ERROR_FLOOR = 1e-6  # the reference itself has error 0: drawn on the floor


def draw_sweep_points(ax, rows):
    """One marker and colour per factor (per method for the method points), value labels;
    filled markers meet the accuracy target."""
    for factor, (marker, colour) in FACTOR_STYLE.items():
        pts = [r for r in rows if r["factor"] == factor]
        if not pts:
            continue
        for r in pts:
            err = max(float(r["error"]), ERROR_FLOOR)
            m = METHOD_MARKER[r["method"]] if factor == "method" else marker
            ax.plot(float(r["cpu_s"]), err, m, color=colour, ms=8 if factor == "method" else 6,
                    mfc=colour if r["meets_target"] else "none")
            label = r["method"] if factor == "method" else f"{float(r['value']):g}"
            ax.annotate(label, (float(r["cpu_s"]), err), fontsize=6, xytext=(3, 3),
                        textcoords="offset points", color=colour)
        ax.plot([], [], marker, color=colour, label=factor)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU time of the envelope [s]")


def fig_pareto(f, out, written, notes):
    """Speed versus accuracy (rendulic sweep): envelope error against CPU time, log-log."""
    g = f["sweep"]
    rows = []
    for name in sorted(g["points"]):
        p = g["points"][name]
        rows.append({k: attr(p, k) for k in p.attrs})
    ok = [r for r in rows if r["status"] == "ok" and r["envelope"] == "elastic"]
    if not ok:
        notes.append("Pareto chart: no elastic point with status ok")
        return
    plastic = [r for r in rows if r["status"] == "ok" and r["envelope"] == "plastic"]
    fig, axes = plt.subplots(1, 2 if plastic else 1, figsize=(15 if plastic else 8.5, 6),
                             squeeze=False)
    ax = axes[0][0]
    draw_sweep_points(ax, ok)
    front = sorted((float(r["cpu_s"]), max(float(r["error"]), ERROR_FLOOR))
                   for r in ok if r["pareto"])
    if front:
        ax.step([x for x, _ in front], [y for _, y in front], where="post", color="0.4",
                lw=1, ls="--", label="Pareto front")
    target = float(attr(g, "target"))
    ax.axhline(target, color="tab:red", lw=0.8, ls=":", label=f"target {target:g}")
    # Settings that could not run, listed at the top edge with the reason.
    bad = [r for r in rows if r["status"] != "ok"]
    for i, r in enumerate(bad):
        ax.annotate(f"{r['factor']} = {float(r['value']):g}: {r['status']}",
                    xy=(0.01, 0.98 - 0.035 * i), xycoords="axes fraction", fontsize=7,
                    color="tab:red", va="top")
    ax.set_ylabel(r"max$_\theta$ $|\delta\sigma^* - \delta\sigma^*_{ref}|$ / $a_{ref}$")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title("Elastic envelope against the linear response (filled: meets the target; "
                 f"the reference itself at {ERROR_FLOOR:g}, off the front)", fontsize=8)
    if plastic:
        bx = axes[0][1]
        draw_sweep_points(bx, plastic)
        bx.set_ylabel("error against the minimisation envelope")
        bx.legend(fontsize=7, loc="upper right")
        bx.set_title("Elasto-plastic envelope, |d eps| = "
                     f"{float(attr(g, 'plastic_amplitude')):g}", fontsize=8)
    breaks = [b for b in str(attr(g, "breaks", "")).split("\n") if b]
    if breaks:
        fig.text(0.01, -0.01, "\n".join(b if len(b) < 170 else b[:167] + "..." for b in breaks),
                 fontsize=6, va="top", ha="left")
    save(fig, out, "pareto", written)


def main():
    if len(sys.argv) != 3:
        print("usage: plot.py FILE.h5 OUTDIR", file=sys.stderr)
        return 2
    path, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    written, notes = [], []
    figures = [
        ("isotropic branch", lambda f: fig_isotropic(f, out, written, notes)),
        ("Fig. 1", lambda f: fig1_path(f, out, written, notes)),
        ("Fig. 2", lambda f: fig2_strain_circle(out, written)),
        ("Fig. 3", lambda f: fig_envelopes(f, out, written, notes, 3, "elastic", "stress")),
        ("Fig. 4", lambda f: fig_envelopes(f, out, written, notes, 4, "elastic", "fabric")),
        ("Fig. 5", lambda f: fig_envelopes(f, out, written, notes, 5, "plastic", "stress")),
        ("Fig. 6", lambda f: fig_envelopes(f, out, written, notes, 6, "plastic", "fabric")),
        ("Fig. 7", lambda f: fig7_trends(f, out, written, notes)),
    ]
    with h5py.File(path, "r") as f:
        if "sweep" in f:  # a sweep file (rendulic sweep) has the Pareto chart only
            figures = [("Pareto chart", lambda f: fig_pareto(f, out, written, notes))]
        for name, draw in figures:
            try:
                draw(f)
            except (KeyError, ValueError, IndexError) as e:  # partial files: skip, say why
                plt.close("all")
                notes.append(f"{name}: {e}")
    for w in written:
        print(w)
    for n in notes:
        print("skipped:", n, file=sys.stderr)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Exception as e:  # noqa: BLE001  data it cannot draw: one line, exit 2 (rendulic's)
        print(f"{type(e).__name__}: {e}".replace("\n", " "), file=sys.stderr)
        sys.exit(2)
