# Figures of a rendulic results file (seed paper Figs. 1-7 and the isotropic branch).
# Embedded into the `rendulic` binary at build time and run by `rendulic plot FILE.h5 --out DIR`
# with Debian's python3-matplotlib and python3-h5py. Reads only the names of docs/results.md
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
ELASTIC_MAX, PLASTIC_MIN = 1e-4, 1e-3  # docs/physics.md section 5


def save(fig, out, name, written, description=None):
    for ext in ("png", "svg"):
        path = os.path.join(out, f"{name}.{ext}")
        meta = {"Description": description} if description else None
        fig.savefig(path, dpi=130, bbox_inches="tight", metadata=meta)
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


def plastic_amplitude(f):
    """The largest probe amplitude of the dynamic campaigns (> 1e-3), or None."""
    amps = []
    for eps, label, g in states(f):
        for name, e in envelopes(g, "plastic"):
            if attr(e, "method") != "linear_response":
                amps.append(float(attr(e, "amplitude", 0.0)))
    return max(amps) if amps else None


def fig_elastic_range(f, out, written, notes):
    """Where each state's response leaves the elastic one (elastic_range stage): b/a, |c|/a
    and k_continue/k_reverse of the four-direction ladder against the amplitude."""
    rows = [(eps, label, g["elastic_range"]) for eps, label, g in states(f)
            if "elastic_range" in g]
    if not rows:
        notes.append("elastic range: no /states/*/elastic_range")
        return
    fig, ax = plt.subplots(1, 4, figsize=(15, 3.5))
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(rows)))
    for (eps, label, g), c in zip(rows, colours):
        a = g["amplitude"][:]
        minor = g["minor_over_elastic"][:] * float(attr(g, "elastic_minor"))
        major = g["major_over_elastic"][:] * float(attr(g, "elastic_major"))
        kc, kr = g["k_continue"][:], g["k_reverse"][:]
        y = float(attr(g, "yield_strain"))
        lab = rf"{label} ($-\varepsilon_{{dev}}$ {-eps:.3f})"
        ax[0].plot(a, minor / major, "o-", color=c, ms=4, label=lab)
        ax[1].plot(a, g["minor_over_elastic"][:], "o-", color=c, ms=4)
        ax[2].plot(a, g["center_over_a"][:], "o-", color=c, ms=4)
        ax[3].plot(a, kc / kr, "o-", color=c, ms=4)
        for x in ax:
            x.axvline(y, color=c, lw=0.8, ls=":")
    tol = float(attr(rows[0][2], "tolerance"))
    ax[1].axhspan(1 - tol, 1 + tol, color="0.9", zorder=0)
    ax[3].axhspan(1 - tol, 1 + tol, color="0.9", zorder=0)
    ax[3].axhline(0.2, color="tab:red", lw=0.8, ls="--")
    pa = plastic_amplitude(f)
    for x in ax:
        x.set_xscale("log")
        x.set_xlabel(r"$|\delta\varepsilon|$")
        if pa:
            x.axvline(pa, color="k", lw=1, ls="--")
    ax[0].set_title("b/a of the ladder's map", fontsize=9)
    ax[1].set_title("minor axis / elastic (band: tolerance)", fontsize=9)
    ax[2].set_title("|centre| / a", fontsize=9)
    ax[3].set_title(r"$k_{continue}/k_{reverse}$ (red: 0.2)", fontsize=9)
    ax[0].legend(fontsize=6)
    fig.suptitle("Elastic range per state (dotted: yield strain; dashed: plastic amplitude)")
    save(fig, out, "elastic_range", written)


def fig_yield_pressure(f, out, written, notes):
    """Yield strain against P* over the volume fractions of the run (pressure stage)."""
    pts = []  # (P*, yield, yielded, nu, label, elastic_to)
    groups = [g for _, _, g in states(f)]
    if "pressure" in f:
        for tag, pg in f["pressure"].items():
            if "states" in pg:
                groups += list(pg["states"].values())
    for g in groups:
        if "elastic_range" not in g:
            continue
        er = g["elastic_range"]
        if attr(g, "pressure_star") is None or attr(g, "volume_fraction") is None:
            continue
        pts.append((float(attr(g, "pressure_star")), float(attr(er, "yield_strain")),
                    int(attr(er, "yielded", 1)), float(attr(g, "volume_fraction")),
                    g.name.split("/")[-1], float(attr(er, "elastic_to", 0.0))))
    nus = sorted({round(p[3], 2) for p in pts})
    if len(nus) < 2:
        notes.append("yield against P*: elastic ranges at fewer than two volume fractions")
        return
    fig, ax = plt.subplots(figsize=(5.5, 4))
    colours = plt.cm.plasma(np.linspace(0, 0.8, len(nus)))
    for nu, c in zip(nus, colours):
        sel = [p for p in pts if round(p[3], 2) == nu]
        for p in sel:
            ax.plot(p[0], p[1], "o" if p[2] else "^", color=c, mfc=c if p[2] else "none")
            if p[5] > 0:  # the bracket: still elastic at elastic_to, departed at the yield
                ax.plot([p[0], p[0]], [p[5], p[1]], "-", color=c, lw=0.6, alpha=0.6)
            ax.annotate(p[4], (p[0], p[1]), fontsize=6, xytext=(3, 2), textcoords="offset points")
        med_p = float(np.median([p[0] for p in sel]))
        med_y = float(np.median([p[1] for p in sel]))
        ax.plot(med_p, med_y, "s", color=c, ms=9, mfc="none", mew=1.5)
        ax.plot([], [], "o", color=c, label=rf"$\nu$ = {nu:.2f} (square: median)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(r"$P^*$")
    ax.set_ylabel("yield strain")
    ax.legend(fontsize=7)
    ax.set_title("Yield strain against pressure (lines: from the last elastic rung; open "
                 "triangle: no departure within the ladder)", fontsize=8)
    save(fig, out, "yield_pressure", written)


# Calibrated laws over the DEM (docs/calibration.md "Model envelopes beside the DEM"): per
# amplitude and quantity one figure, one panel per state, with the DEM points (the probe
# method the claims use: dynamic, else minimisation, else the linear response at elastic
# amplitude), the DEM fit, and every calibrated law's envelope for the same probes; and the
# path with every law's prediction. The SVG description lists the laws drawn.
MODEL_COLOURS = ["tab:red", "tab:green", "tab:purple", "tab:brown", "tab:olive", "tab:cyan"]


def calibrated_models(f):
    """(name, group, label) of every calibrated law; the selected one is marked."""
    if "calibration" not in f:
        return []
    sel = attr(f["calibration"], "selected_model", "")
    out = []
    for name, g in f["calibration"].items():
        if not isinstance(g, h5py.Group) or attr(g, "error") is not None:
            continue
        out.append((name, g, name + (" (selected)" if name == sel else "")))
    return out


def dem_envelope(state_group, kind):
    """The DEM envelope a panel shows: dynamic, else minimisation, else (elastic only) the
    linear response; returns (name, group) or None."""
    envs = envelopes(state_group, kind)
    for method in ("dynamic", "minimisation", "linear_response"):
        if method == "linear_response" and kind != "elastic":
            continue
        for name, g in envs:
            if attr(g, "method") == method:
                return name, g
    return None


def closed(theta, pts):
    order = np.argsort(theta)
    p = np.asarray(pts)[order]
    return np.vstack([p, p[:1]])


def fig_model_envelopes(f, out, written, notes, kind, quantity):
    models = calibrated_models(f)
    if not models:
        notes.append(f"models {kind} {quantity}: no calibrated law")
        return
    k_star = float(attr(f["material"], "k_star", 1.0)) if "material" in f else 1.0
    panels = []
    for eps, label, g in states(f):
        env = dem_envelope(g, kind)
        if env is not None:
            panels.append((eps, label, env))
    if not panels:
        notes.append(f"models {kind} {quantity}: no {kind} DEM envelopes")
        return
    key = "stress_star" if quantity == "stress" else "fabric"
    fit_key = "fit_stress" if quantity == "stress" else "fit_fabric"
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(3.4 * n, 3.6), squeeze=False)
    drawn, no_fabric = set(), set()
    for ax, (eps, label, (name, g)) in zip(axes[0], panels):
        r = g[key][:]
        ax.plot(r[:, 0], r[:, 1], "k.", ms=4, label=f"DEM ({attr(g, 'method', '?')})")
        if fit_key in g:
            x, y = fit_curve(g[fit_key])
            ax.plot(x, y, "k-", lw=0.8, label="DEM fit")
        for i, (mname, mg, mlabel) in enumerate(models):
            path = f"states/{label}/envelopes/{name}"
            if path not in mg:
                continue
            e = mg[path]
            pred = e["stress"][:] / k_star if quantity == "stress" else e["fabric"][:]
            if quantity == "fabric" and not np.any(pred):
                no_fabric.add(mname)  # a law without fabric (hypoplastic_wu): nothing to draw
                continue
            c = closed(e["theta_deg"][:], pred)
            ax.plot(c[:, 0], c[:, 1], "-", color=MODEL_COLOURS[i % len(MODEL_COLOURS)], lw=1.2,
                    label=mlabel)
            drawn.add(mname)
        ax.axhline(0, color="0.85", lw=0.6)
        ax.axvline(0, color="0.85", lw=0.6)
        ax.set_title(rf"{label}: $-\varepsilon_{{dev}}$ = {-eps:.3f}, "
                     f"|δε| = {float(attr(g, 'amplitude', 0)):g}", fontsize=8)
        sym = "\\sigma^*" if quantity == "stress" else "F"
        ax.set_xlabel(r"$\sqrt{2}\,\delta " + sym + r"_{yy}$")
        ax.tick_params(labelsize=7)
    sym = "\\sigma^*" if quantity == "stress" else "F"
    axes[0][0].set_ylabel(r"$\delta " + sym + r"_{xx}$")
    axes[0][0].legend(fontsize=6)
    title = f"Calibrated laws over the DEM: {kind} {quantity} envelopes"
    if no_fabric:
        title += " (no fabric predicted by " + ", ".join(sorted(no_fabric)) + ")"
    fig.suptitle(title, y=1.06)  # above the panels' titles and axis offsets
    desc = "models: " + ", ".join(sorted(drawn))
    if no_fabric:
        desc += "; no fabric: " + ", ".join(sorted(no_fabric))
    save(fig, out, f"models_{kind}_{quantity}", written, description=desc)


def fig_models_path(f, out, written, notes):
    models = [m for m in calibrated_models(f) if "path" in m[1]]
    if "path" not in f or not models:
        notes.append("models path: no path or no law with a predicted path")
        return
    g = f["path"]
    k_star = float(attr(f["material"], "k_star", 1.0)) if "material" in f else 1.0
    e0 = float(g["eps_dev"][0])
    x = -g["eps_dev"][:]
    s, F = g["stress_star"][:], g["fabric"][:]
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    for i, lab in ((0, "xx"), (1, "yy")):
        ax[0].plot(x, s[:, i, i], "k-" if i == 0 else "k--", lw=1.4,
                   label=rf"DEM $\sigma^*_{{{lab}}}$")
        ax[1].plot(x, F[:, i, i], "k-" if i == 0 else "k--", lw=1.4, label=f"DEM $F_{{{lab}}}$")
    drawn = []
    for j, (mname, mg, mlabel) in enumerate(models):
        p = mg["path"]
        xm = -(e0 + p["eps_dev"][:])
        sm, fm = p["stress"][:] / k_star, p["fabric"][:]
        c = MODEL_COLOURS[j % len(MODEL_COLOURS)]
        for i in (0, 1):
            ls = "-" if i == 0 else "--"
            ax[0].plot(xm, sm[:, i, i], ls, color=c, lw=1, label=mlabel if i == 0 else None)
            ax[1].plot(xm, fm[:, i, i], ls, color=c, lw=1, label=mlabel if i == 0 else None)
        drawn.append(mname)
    # The DEM sets the scale: a law far off leaves the frame rather than flatten the data.
    for a, d in ((ax[0], s), (ax[1], F)):
        lo = min(d[:, 0, 0].min(), d[:, 1, 1].min())
        hi = max(d[:, 0, 0].max(), d[:, 1, 1].max())
        a.set_ylim(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo))
    for a in ax:
        a.set_xlabel(r"$-\varepsilon_{dev}$")
        a.legend(fontsize=6)
    ax[0].set_title("(a) stress: xx solid, yy dashed")
    ax[1].set_title("(b) fabric: xx solid, yy dashed")
    fig.suptitle("Calibrated laws along the main path (Fig. 1 analogue)")
    save(fig, out, "models_path", written, description="models: " + ", ".join(sorted(drawn)))


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
    if "points" not in g:
        notes.append("Pareto chart: no probe-method points (path_rate only)")
        return
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


def fig_path_rate(f, out, written, notes):
    """The path's rate (rendulic sweep, factor path_rate): the steady-state stress ratio
    against the inertial number, each seed and their mean with its standard error."""
    g = f["sweep"]
    if "path_rate" not in g:
        return
    rows = [g["path_rate"][k] for k in sorted(g["path_rate"])]
    ok = [r for r in rows if attr(r, "status") == "ok"]
    if not ok:
        notes.append("path rate: no point with status ok")
        return
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for r in ok:
        i = float(attr(r, "inertial_number"))
        seeds = np.atleast_1d(np.asarray(attr(r, "ratio_per_seed", []), dtype=float))
        ax.plot([i] * len(seeds), seeds, ".", color="0.6", ms=4)
        filled = int(attr(r, "converged", 0)) == 1
        ax.errorbar(i, float(attr(r, "ratio")), yerr=float(attr(r, "ratio_stderr")), fmt="o",
                    color="tab:blue", mfc="tab:blue" if filled else "white", capsize=3)
        ax.annotate(f"{float(attr(r, 'rate')):g}/s", (i, float(attr(r, "ratio"))), fontsize=6,
                    xytext=(4, 4), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_xlabel("inertial number of the path (steady state)")
    ax.set_ylabel(r"steady-state $|\sigma_{dev}|/P$")
    target = float(attr(g, "path_rate_target", 0.02))
    ax.set_title("Path rate: mean +- standard error over seeds (grey: each seed); filled: "
                 f"within {100 * target:g} % of the run 4x slower", fontsize=8)
    save(fig, out, "path_rate", written)


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
        ("elastic range", lambda f: fig_elastic_range(f, out, written, notes)),
        ("yield against P*", lambda f: fig_yield_pressure(f, out, written, notes)),
        ("models elastic stress",
         lambda f: fig_model_envelopes(f, out, written, notes, "elastic", "stress")),
        ("models plastic stress",
         lambda f: fig_model_envelopes(f, out, written, notes, "plastic", "stress")),
        ("models elastic fabric",
         lambda f: fig_model_envelopes(f, out, written, notes, "elastic", "fabric")),
        ("models plastic fabric",
         lambda f: fig_model_envelopes(f, out, written, notes, "plastic", "fabric")),
        ("models path", lambda f: fig_models_path(f, out, written, notes)),
    ]
    with h5py.File(path, "r") as f:
        if "sweep" in f:  # a sweep file (rendulic sweep): the Pareto and path-rate charts
            figures = [("Pareto chart", lambda f: fig_pareto(f, out, written, notes)),
                       ("path rate", lambda f: fig_path_rate(f, out, written, notes))]
        for name, draw in figures:
            try:
                draw(f)
            except (KeyError, ValueError, IndexError, TypeError) as e:  # partial files: skip
                # and say why
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
