# Figures of a rendulic results file (seed paper Figs. 1-7, the isotropic branch, elastic
# ranges, calibrated laws; a sweep file's Pareto and path-rate charts). docs/figures.md lists
# them and says how to restyle them. Reads only the names of docs/results.md (schema
# rendulic/1), so it works on any conforming file; a figure whose data is absent is skipped
# with a note, never faked. Writes each figure as PNG (300 dpi), PDF and SVG, sized for a
# journal page (7 in wide, the Rendulic planes equal-aspect in a grid).
#
# `rendulic plot` runs this file: the copy named by --script or RENDULIC_PLOT_SCRIPT, else the
# one installed beside the binary (share/rendulic/plot.py), else the copy compiled into the
# binary. Edit an installed copy to restyle; `python3 plot.py FILE.h5 OUTDIR` runs it alone
# with Debian's python3-matplotlib and python3-h5py.
import math
import os
import stat
import sys
import textwrap

try:
    import h5py
    import matplotlib
except ImportError as e:  # exit 3: `rendulic plot` runs the script with the next interpreter
    print(f"plot.py needs h5py and matplotlib: {e}", file=sys.stderr)
    sys.exit(3)

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.transforms as mtransforms  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import FuncFormatter, MaxNLocator, NullLocator  # noqa: E402

# --- style: the one place to restyle every figure -------------------------------------------
FORMATS = ("png", "pdf", "svg")
PNG_DPI = 300
PAGE_WIDTH = 7.0  # inches: a two-column journal figure (one column is about 3.4 in)
STYLE = {
    "font.size": 8, "axes.titlesize": 8, "axes.labelsize": 8, "xtick.labelsize": 7,
    "ytick.labelsize": 7, "legend.fontsize": 7, "figure.titlesize": 9, "lines.linewidth": 1.0,
    "lines.markersize": 4, "axes.linewidth": 0.6, "legend.frameon": False,
    # No offset text ("1e-5" above an axis): the Rendulic planes and Fig. 1 put the power of
    # ten into the axis label instead.
    "axes.formatter.useoffset": False,
    "svg.fonttype": "none", "pdf.fonttype": 42,
}
# Probe methods: linear_response (the exact elastic reference) is a small dot drawn on top,
# the probes open markers around it, so coincident points stay visible.
METHODS = {
    "dynamic": dict(marker="o", ms=5, mfc="none", mew=0.9, color="tab:blue", zorder=4,
                    fit_ls="-"),
    "minimisation": dict(marker="s", ms=4.5, mfc="none", mew=0.9, color="tab:orange",
                         zorder=3, fit_ls=":"),
    "linear_response": dict(marker=".", ms=4.5, mfc="tab:green", mew=0.0, color="tab:green",
                            zorder=5, fit_ls="--"),
}
DRAW_ORDER = ("minimisation", "dynamic", "linear_response")
MODEL_COLOURS = ["tab:red", "tab:green", "tab:purple", "tab:brown", "tab:olive", "tab:cyan"]

ISO = math.degrees(math.atan(1 / math.sqrt(2)))  # 35.26 deg
# Special strain directions (docs/physics.md): families with their marker.
SPECIAL = {"I.C.": ISO, "I.E.": ISO + 180, "U.C.": 90.0, "U.E.": 270.0,
           "D.C.": ISO + 90, "D.E.": ISO + 270}
SPECIAL_FAMILIES = [
    ("I", "o", "isotropic I.C./I.E. (35.26°, 215.26°)"),
    ("U", "s", "uniaxial U.C./U.E. (90°, 270°)"),
    ("D", "D", "constant volume D.C./D.E. (125.26°, 305.26°)"),
]
ELASTIC_MAX, PLASTIC_MIN = 1e-4, 1e-3  # docs/physics.md section 5
RENDULIC_GID = "rendulic-plane"  # gid of every Rendulic-plane axes (tests find them by it)


def save(fig, out, name, ctx, description=None):
    meta = {"Description": description} if description else {}
    # The tight bounding box once for the three formats: bbox_inches="tight" would draw the
    # whole figure a second time per format just to find it (a third of the drawing time).
    box = fig.get_tightbbox(fig.canvas.get_renderer()).padded(plt.rcParams["savefig.pad_inches"])
    for ext in FORMATS:
        path = os.path.join(out, f"{name}.{ext}")
        # PNG takes no "Description" key in every matplotlib; the SVG and PDF carry it.
        md = meta if ext == "svg" else ({"Subject": description} if ext == "pdf" and
                                        description else None)
        # Whole or not at all, as every file rendulic writes (docs/usage.md "Results are
        # atomic"): a full disk must not leave a truncated figure under its name.
        tmp = os.path.join(out, f".{name}.{ext}.tmp-{os.getpid()}")
        # A figure the user may not write is not replaced, and a replaced one keeps its
        # permissions (owner and group where allowed), as the binary's files (same page).
        try:
            before = os.stat(path)
        except FileNotFoundError:
            before = None
        if before is not None and not os.access(path, os.W_OK):
            raise OSError(f"{path}: cannot write the figure: Permission denied")
        try:
            fig.savefig(tmp, format=ext, dpi=PNG_DPI, bbox_inches=box, metadata=md)
            if before is not None:
                try:
                    os.chown(tmp, before.st_uid if os.geteuid() == 0 else -1, before.st_gid)
                except OSError:
                    pass
                os.chmod(tmp, stat.S_IMODE(before.st_mode))
            os.replace(tmp, path)
        except BaseException:
            try:
                os.remove(tmp)
            except OSError:
                pass
            raise
        ctx["written"].append(path)
    if ctx.get("keep") is not None:
        ctx["keep"][name] = fig
    else:
        plt.close(fig)


def attr(obj, name, default=None):
    """An attribute; byte strings decoded, string arrays as lists of str."""
    v = obj.attrs.get(name, default)
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.ndarray) and v.dtype.kind in ("O", "S", "U"):
        return [x.decode() if isinstance(x, bytes) else str(x) for x in v.ravel()]
    return v


def finite(g, name):
    """Dataset `name` of group `g` as a float array. rendulic never stores a value that is not
    finite in the series and envelope pairs the figures draw, so one is damage: the figure is
    skipped naming it (matplotlib left such a point out without a word)."""
    a = np.asarray(g[name][:], dtype=float)
    bad = np.flatnonzero(~np.isfinite(a.reshape(len(a), -1)).all(axis=1)) if a.size else []
    if len(bad):
        raise ValueError(f"{g.name}/{name}: row {bad[0]} is not finite")
    return a


def attr_list(obj, name, sep=","):
    """A list attribute stored either as one `sep`-joined string or as an HDF5 string array
    (files of either form exist: docs/results.md)."""
    v = attr(obj, name)
    if v is None:
        return []
    if isinstance(v, list):
        return [x for x in v if x]
    return [x.strip() for x in str(v).split(sep) if x.strip()]


def states(f):
    if "states" not in f:
        return []
    out = [(float(attr(g, "eps_dev", 0.0)), label, g) for label, g in f["states"].items()]
    return sorted(out, key=lambda t: -t[0])  # -eps_dev increasing (extension: eps_dev < 0)


def rendulic_plane(g):
    """Whether an envelope's pairs are Rendulic pairs: the figures draw Rendulic planes, an
    envelope of another probe plane (docs/probes.md "Probe planes") is listed by the report."""
    return str(attr(g, "plane", "rendulic")) == "rendulic"


def envelopes(state_group, kind):
    """Rendulic-plane envelopes of a state that are elastic (amplitude < 1e-4) or plastic
    (> 1e-3)."""
    if "envelopes" not in state_group:
        return []
    out = []
    for name, g in state_group["envelopes"].items():
        if not rendulic_plane(g):
            continue
        a = float(attr(g, "amplitude", 0.0))
        if (kind == "elastic" and a < ELASTIC_MAX) or (kind == "plastic" and a > PLASTIC_MIN):
            out.append((name, g))
    return out


def fit_ok(fit):
    return fit is not None and attr(fit, "shape", "none") in ("ellipse", "line", "circle")


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


# --- layout helpers -------------------------------------------------------------------------
def power_of_ten(*arrays):
    """The power of ten that brings the data to 0.1-1000, 0 when it is there already."""
    m = 0.0
    for a in arrays:
        a = np.asarray(a, dtype=float)
        if a.size:
            v = np.nanmax(np.abs(a))
            if np.isfinite(v):
                m = max(m, float(v))
    if m <= 0:
        return 0
    e = int(math.floor(math.log10(m)))
    return 0 if -1 <= e <= 2 else e


def with_power(label, e):
    return label if e == 0 else label + rf" [$10^{{{e}}}$]"


def panel_grid(n_panels, legend_cell=True, ncols=3):
    """Square panels in rows of `ncols` across the page; with legend_cell, the cell after the
    last panel (or a row of its own) holds the legend. Returns fig, panel axes, legend axes."""
    cells = n_panels + (1 if legend_cell else 0)
    ncols = max(1, min(ncols, cells))
    nrows = math.ceil(cells / ncols)
    side = PAGE_WIDTH / max(ncols, 2)
    # Each row: a square panel, its title above and the axis label below.
    fig, axes = plt.subplots(nrows, ncols, figsize=(side * ncols, (side - 0.2) * nrows + 0.5),
                             squeeze=False)
    flat = list(axes.ravel())
    for ax in flat[n_panels:]:
        ax.axis("off")
    leg = flat[n_panels] if legend_cell else None
    return fig, flat[:n_panels], leg


def rendulic_axes(ax, xs, ys, tag):
    """Equal aspect and square limits around the data points (not the fits: a fit far off
    leaves the frame rather than shrink the data), axes through the origin."""
    x = np.concatenate([np.ravel(v) for v in xs]) if xs else np.zeros(1)
    y = np.concatenate([np.ravel(v) for v in ys]) if ys else np.zeros(1)
    x, y = x[np.isfinite(x)], y[np.isfinite(y)]
    if not x.size or not y.size:
        x, y = np.zeros(1), np.zeros(1)
    cx, cy = 0.5 * (x.min() + x.max()), 0.5 * (y.min() + y.max())
    h = 0.5 * max(x.max() - x.min(), y.max() - y.min()) * 1.12
    if h <= 0:
        h = max(abs(cx), abs(cy), 1.0) * 0.1
    ax.set_xlim(cx - h, cx + h)
    ax.set_ylim(cy - h, cy + h)
    ax.set_aspect("equal", adjustable="box")
    ax.axhline(0, color="0.85", lw=0.6, zorder=0)
    ax.axvline(0, color="0.85", lw=0.6, zorder=0)
    ax.xaxis.set_major_locator(MaxNLocator(4))
    ax.yaxis.set_major_locator(MaxNLocator(4))
    ax.set_gid(f"{RENDULIC_GID}-{tag}")


def rendulic_labels(ax, sym, e, first_in_row):
    ax.set_xlabel(with_power(r"$\sqrt{2}\,\delta " + sym + r"_{yy}$", e))
    if first_in_row:
        ax.set_ylabel(with_power(r"$\delta " + sym + r"_{xx}$", e))


def legend_in(cell, handles, title=None):
    """The figure's legend in its own cell (one legend for all panels)."""
    if cell is None:
        return
    cell.legend(handles=handles, loc="center", title=title, fontsize=7, title_fontsize=7)


def special_handles(present):
    return [Line2D([], [], ls="none", marker=m, mfc="none", mec="k", ms=7, label=lab)
            for fam, m, lab in SPECIAL_FAMILIES if fam in present]


def mark_special(ax, theta, xy, annotate):
    """Black open markers (one shape per family) at the probes along special directions;
    returns the families found."""
    found = set()
    if theta is None:
        return found
    for name, deg in SPECIAL.items():
        d = np.abs(((theta - deg + 180) % 360) - 180)
        i = int(np.argmin(d))
        if d[i] > 1e-6:
            continue
        fam = name[0]
        m = next(mm for f, mm, _ in SPECIAL_FAMILIES if f == fam)
        ax.plot(xy[i, 0], xy[i, 1], ls="none", marker=m, mfc="none", mec="k", ms=7, mew=0.8,
                zorder=6)
        if annotate:  # the name outside the envelope, away from its centroid
            d = xy[i] - np.mean(xy, axis=0)
            n = float(np.hypot(d[0], d[1])) or 1.0
            ax.annotate(name, (xy[i, 0], xy[i, 1]), xytext=(9 * d[0] / n, 9 * d[1] / n),
                        textcoords="offset points", fontsize=6, zorder=7,
                        ha="left" if d[0] >= 0 else "right", va="bottom" if d[1] >= 0 else "top")
        found.add(fam)
    return found


def state_title(label, eps):
    return rf"{label}: $-\varepsilon_{{dev}}$ = {-eps:.3f}"


# --- figures --------------------------------------------------------------------------------
def fig_isotropic(f, out, ctx):
    if "isotropic" not in f:
        ctx["notes"].append("isotropic branch: no /isotropic")
        return
    g = f["isotropic"]
    nu = finite(g, "volume_fraction")
    p = finite(g, "pressure_star")
    fig, ax = plt.subplots(1, 2, figsize=(PAGE_WIDTH, 2.8))
    e = power_of_ten(p)
    ax[0].plot(nu, p / 10.0 ** e, ".-")
    ax[0].set_xlabel(r"volume fraction $\nu$")
    ax[0].set_ylabel(with_power(r"$P^*$", e))
    ax[1].plot(nu, g["coordination_nonrattler"][:], ".-", label=r"$C^*$ (without rattlers)")
    ax[1].plot(nu, g["coordination"][:], ".-", label="$C$")
    ax[1].set_xlabel(r"volume fraction $\nu$")
    ax[1].set_ylabel("coordination number")
    ax[1].legend()
    ax[0].set_title("(a) pressure")
    ax[1].set_title("(b) coordination")
    fig.suptitle("Isotropic branch")
    fig.tight_layout()
    save(fig, out, "isotropic_branch", ctx)


def mark_states(ax, f):
    """Dotted vertical lines at the states, labelled with their names along the top."""
    for eps, label, _ in states(f):
        ax.axvline(-eps, color="0.6", lw=0.7, ls=":", zorder=0)
        ax.text(-eps, 1.0, label, transform=ax.get_xaxis_transform(), ha="center",
                va="bottom", fontsize=7, color="0.3")


def fig1_path(f, out, ctx):
    if "path" not in f:
        ctx["notes"].append("Fig. 1: no /path")
        return
    g = f["path"]
    x = -finite(g, "eps_dev")
    s, F = finite(g, "stress_star"), finite(g, "fabric")
    fig, ax = plt.subplots(1, 2, figsize=(PAGE_WIDTH, 3.0))
    es = power_of_ten(*(s[:, i, i] for i in range(3)))
    for i, (lab, ls) in enumerate((("xx", "-"), ("yy", "--"), ("zz", ":"))):
        ax[0].plot(x, s[:, i, i] / 10.0 ** es, ls, label=rf"$\sigma^*_{{{lab}}}$")
        ax[1].plot(x, F[:, i, i], ls, label=f"$F_{{{lab}}}$")
    for a in ax:
        mark_states(a, f)
        a.set_xlabel(r"$-\varepsilon_{dev}$")
        a.legend()
    ax[0].set_ylabel(with_power(r"stress $\sigma^*_{ii}$", es))
    ax[1].set_ylabel(r"fabric $F_{ii}$")
    ax[0].set_title("(a) stress", pad=12)
    ax[1].set_title("(b) fabric", pad=12)
    fig.suptitle("Fig. 1: the undrained path (dotted: the states, labelled above)")
    fig.tight_layout()
    save(fig, out, "fig1_path", ctx)


def fig2_strain_circle(f, out, ctx):
    """The run's own strain probes: every direction and amplitude stored in its envelopes,
    normalised to the unit circle, with the special directions."""
    dirs, amps, methods = None, set(), set()
    for eps, label, g in states(f):
        if "envelopes" not in g:
            continue
        for name, e in g["envelopes"].items():
            if "strain" not in e or not rendulic_plane(e):
                continue
            s = finite(e, "strain")
            n = np.linalg.norm(s, axis=1)
            if not np.all(n > 0):
                continue
            if dirs is None:
                dirs = s / n[:, None]
            amps.add(float(attr(e, "amplitude", 0.0)))
            methods.add(str(attr(e, "method", "?")))
    if dirs is None:
        ctx["notes"].append("Fig. 2: no probe envelopes with strains")
        return
    fig, ax = plt.subplots(figsize=(3.4, 3.4))
    t = np.linspace(0, 2 * math.pi, 300)
    ax.plot(np.cos(t), np.sin(t), "-", color="0.6", lw=0.8, zorder=1)
    ax.plot(dirs[:, 0], dirs[:, 1], "o", ms=3.5, color="tab:blue", zorder=3)
    colours = {"I": "tab:red", "U": "tab:green", "D": "tab:purple"}
    for name, deg in SPECIAL.items():
        r = math.radians(deg)
        ax.plot([0, math.cos(r)], [0, math.sin(r)], lw=0.8, color=colours[name[0]], zorder=2)
        ax.annotate(f"{name}\n{deg:.2f}°", (1.22 * math.cos(r), 1.22 * math.sin(r)),
                    ha="center", va="center", fontsize=6)
    ax.set_xlim(-1.45, 1.45)
    ax.set_ylim(-1.45, 1.45)
    ax.set_aspect("equal", adjustable="box")
    ax.set_gid(f"{RENDULIC_GID}-fig2")
    ax.set_xlabel(r"$\sqrt{2}\,\delta\varepsilon_{yy}/|\delta\varepsilon|$")
    ax.set_ylabel(r"$\delta\varepsilon_{xx}/|\delta\varepsilon|$")
    amp = ", ".join(f"{a:g}" for a in sorted(amps))
    ax.set_title(f"Fig. 2: the run's {len(dirs)} strain probes (dots)\n|δε| = {amp}; "
                 + ", ".join(sorted(methods)), fontsize=8)
    save(fig, out, "fig2_strain_circle", ctx)


def fig_envelopes(f, out, ctx, number, kind, quantity):
    found = [(eps, label, envelopes(g, kind)) for eps, label, g in states(f)]
    found = [x for x in found if x[2]]
    if not found:
        ctx["notes"].append(f"Fig. {number}: no {kind} envelopes")
        return
    key = "stress_star" if quantity == "stress" else "fabric"
    fit_key = "fit_stress" if quantity == "stress" else "fit_fabric"
    sym = "\\sigma^*" if quantity == "stress" else "F"
    e = power_of_ten(*(finite(g, key) for _, _, envs in found for _, g in envs if key in g))
    scale = 10.0 ** e
    fig, axes, leg = panel_grid(len(found))
    ncols = fig.axes[0].get_subplotspec().get_gridspec().ncols
    handles, seen, families = {}, set(), set()
    for k, (ax, (eps, label, envs)) in enumerate(zip(axes, found)):
        by_method = {attr(g, "method", "?"): g for _, g in envs if key in g}
        xs, ys, shapes = [], [], []
        primary = next((m for m in ("dynamic", "minimisation", "linear_response")
                        if m in by_method), None)
        for method in sorted(by_method, key=lambda m: DRAW_ORDER.index(m)
                             if m in DRAW_ORDER else -1):
            g = by_method[method]
            st = METHODS.get(method, dict(marker="x", ms=4, mfc="k", mew=0.8, color="k",
                                          zorder=3, fit_ls="-."))
            r = finite(g, key) / scale
            xs.append(r[:, 0])
            ys.append(r[:, 1])
            ax.plot(r[:, 0], r[:, 1], ls="none", marker=st["marker"], ms=st["ms"],
                    mfc=st["mfc"], mec=st["color"], mew=st["mew"], zorder=st["zorder"])
            if method not in handles:
                handles[method] = Line2D([], [], ls="none", marker=st["marker"], ms=st["ms"],
                                         mfc=st["mfc"], mec=st["color"], mew=st["mew"],
                                         label=f"{method} ({float(attr(g, 'amplitude', 0)):g})")
            fit = g.get(fit_key)
            if fit_ok(fit):
                x, y = fit_curve(fit)
                shape = attr(fit, "shape")
                ax.plot(x / scale, y / scale, st["fit_ls"], color=st["color"], lw=0.9, zorder=2)
                shapes.append((shape, st["color"]))
                if (method, shape) not in seen:
                    seen.add((method, shape))
                    handles[(method, shape)] = Line2D([], [], ls=st["fit_ls"], color=st["color"],
                                                      lw=0.9, label=f"{method} fit: {shape}")
            if method == primary:
                th = finite(g, "theta_deg") if "theta_deg" in g else None
                families |= mark_special(ax, th, r, annotate=(k == 0))
        rendulic_axes(ax, xs, ys, label)
        rendulic_labels(ax, sym, e, k % ncols == 0)
        ax.set_title(state_title(label, eps))
        for j, (shape, colour) in enumerate(shapes):  # the chosen shapes, in the fits' colours
            ax.text(0.97, 0.03 + 0.075 * j, shape, transform=ax.transAxes, ha="right",
                    va="bottom", fontsize=6, color=colour)
    points = [h for k, h in handles.items() if isinstance(k, str)]
    fits = [h for k, h in handles.items() if not isinstance(k, str)]
    legend_in(leg, points + fits + special_handles(families),
              title="fit shape: F-test (docs/fitting.md)")
    fig.suptitle(f"Fig. {number}: {kind} {quantity} response envelopes")
    fig.tight_layout()
    save(fig, out, f"fig{number}_{kind}_{quantity}", ctx)


def feature_rows(f, kind):
    """Per state the probe envelope's fitted features with their standard errors: -eps_dev,
    stress inclination, fabric inclination, major and minor semi-axes (value, error)."""
    rows = []
    for eps, label, g in states(f):
        env = dem_envelope(g, kind, probes_only=True)
        if env is None:
            continue
        fs, ff = env[1].get("fit_stress"), env[1].get("fit_fabric")
        if not fit_ok(fs):
            continue
        sa = np.asarray(attr(fs, "semi_axes", [np.nan, np.nan]), dtype=float)
        se = np.asarray(attr(fs, "semi_axes_stderr", [np.nan, np.nan]), dtype=float)
        inc_s = float(attr(fs, "inclination_deg", np.nan))
        inc_s_se = float(attr(fs, "inclination_deg_stderr", np.nan))
        inc_f = float(attr(ff, "inclination_deg", np.nan)) if fit_ok(ff) else np.nan
        inc_f_se = float(attr(ff, "inclination_deg_stderr", np.nan)) if fit_ok(ff) else np.nan
        rows.append((-eps, inc_s, inc_s_se, inc_f, inc_f_se, sa[0], se[0], sa[1], se[1]))
    return np.array(sorted(rows), dtype=float) if rows else None


def ratio_with_error(v, se, i0=0):
    """v / v[0] and its first-order standard error (independent fits)."""
    v0, s0 = v[i0], se[i0]
    if not np.isfinite(v0) or v0 == 0:
        return v, se
    r = v / v0
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.sqrt(np.nan_to_num((se / v) ** 2) + np.nan_to_num((s0 / v0) ** 2))
    return r, np.abs(r) * rel


def fig7_trends(f, out, ctx):
    data = {kind: feature_rows(f, kind) for kind in ("elastic", "plastic")}
    if all(v is None for v in data.values()):
        ctx["notes"].append("Fig. 7: no fitted probe envelopes")
        return
    fig, axes = plt.subplots(2, 2, figsize=(PAGE_WIDTH, 5.2))
    ax = axes.ravel()
    titles = [r"(a) stress inclination $\theta_\sigma$ [deg]",
              r"(b) fabric inclination $\theta_F$ [deg]",
              "(c) major semi-axis / first state", "(d) minor semi-axis / first state"]
    for kind, style, colour in (("elastic", "o", "tab:blue"), ("plastic", "s", "tab:orange")):
        a = data[kind]
        if a is None:
            continue
        kw = dict(fmt=style + "-", color=colour, capsize=2.5, ms=4, lw=0.9, elinewidth=0.8,
                  mfc="none" if kind == "elastic" else colour, label=kind)
        x = a[:, 0]
        ax[0].errorbar(x, a[:, 1], yerr=np.nan_to_num(a[:, 2]), **kw)
        ax[1].errorbar(x, a[:, 3], yerr=np.nan_to_num(a[:, 4]), **kw)
        r, se = ratio_with_error(a[:, 5], a[:, 6])
        ax[2].errorbar(x, r, yerr=np.nan_to_num(se), **kw)
        r, se = ratio_with_error(a[:, 7], a[:, 8])
        ax[3].errorbar(x, r, yerr=np.nan_to_num(se), **kw)
    for a in ax[:2]:
        a.axhline(ISO, color="tab:red", lw=0.7, ls="--", label="isotropic 35.26°")
    for a, t in zip(ax, titles):
        a.set_title(t)
        a.set_xlabel(r"$-\varepsilon_{dev}$")
    ax[0].legend()
    fig.suptitle("Fig. 7: envelope features along the path (bars: standard errors of the fits)")
    fig.tight_layout()
    save(fig, out, "fig7_features", ctx)


def plastic_amplitude(f):
    """The largest probe amplitude of the dynamic campaigns (> 1e-3), or None."""
    amps = []
    for eps, label, g in states(f):
        for name, e in envelopes(g, "plastic"):
            if attr(e, "method") != "linear_response":
                amps.append(float(attr(e, "amplitude", 0.0)))
    return max(amps) if amps else None


def fig_elastic_range(f, out, ctx):
    """Where each state's response leaves the elastic one (elastic_range stage): b/a, |c|/a
    and k_continue/k_reverse of the four-direction ladder against the amplitude."""
    rows = [(eps, label, g["elastic_range"]) for eps, label, g in states(f)
            if "elastic_range" in g]
    if not rows:
        ctx["notes"].append("elastic range: no /states/*/elastic_range")
        return
    fig, axes = plt.subplots(2, 2, figsize=(PAGE_WIDTH, 5.4))
    ax = axes.ravel()
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(rows)))
    for (eps, label, g), c in zip(rows, colours):
        a = g["amplitude"][:]
        minor = g["minor_over_elastic"][:] * float(attr(g, "elastic_minor"))
        major = g["major_over_elastic"][:] * float(attr(g, "elastic_major"))
        kc, kr = g["k_continue"][:], g["k_reverse"][:]
        y = float(attr(g, "yield_strain"))
        lab = rf"{label} ($-\varepsilon_{{dev}}$ {-eps:.3f})"
        ax[0].plot(a, minor / major, "o-", color=c, ms=3.5, label=lab)
        ax[1].plot(a, g["minor_over_elastic"][:], "o-", color=c, ms=3.5)
        ax[2].plot(a, g["center_over_a"][:], "o-", color=c, ms=3.5)
        ax[3].plot(a, kc / kr, "o-", color=c, ms=3.5)
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
    ax[0].set_title("(a) b/a of the ladder's map")
    ax[1].set_title("(b) minor axis / elastic (band: tolerance)")
    ax[2].set_title("(c) |centre| / a")
    ax[3].set_title(r"(d) $k_{continue}/k_{reverse}$ (red: 0.2)")
    ax[0].legend(fontsize=6)
    fig.suptitle("Elastic range per state (dotted: yield strain; dashed: plastic amplitude)")
    fig.tight_layout()
    save(fig, out, "elastic_range", ctx)


def fig_yield_pressure(f, out, ctx):
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
        ctx["notes"].append("yield against P*: elastic ranges at fewer than two volume fractions")
        return
    fig, ax = plt.subplots(figsize=(4.6, 3.6))
    colours = plt.cm.plasma(np.linspace(0, 0.8, len(nus)))
    for nu, c in zip(nus, colours):
        sel = [p for p in pts if round(p[3], 2) == nu]
        for p in sel:
            ax.plot(p[0], p[1], "o" if p[2] else "^", color=c, mfc=c if p[2] else "none")
            if p[5] > 0:  # the bracket: still elastic at elastic_to, departed at the yield
                ax.plot([p[0], p[0]], [p[5], p[1]], "-", color=c, lw=0.6, alpha=0.6)
        med_p = float(np.median([p[0] for p in sel]))
        med_y = float(np.median([p[1] for p in sel]))
        ax.plot(med_p, med_y, "s", color=c, ms=9, mfc="none", mew=1.5)
        ax.plot([], [], "o", color=c, label=rf"$\nu$ = {nu:.2f}")
    place_labels(ax, [(p[0], p[1], p[4], "0.2") for p in pts])
    ax.plot([], [], "s", color="0.3", mfc="none", ms=8, label="median")
    ax.plot([], [], "^", color="0.3", mfc="none", label="no departure in the ladder")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(r"$P^*$")
    ax.set_ylabel("yield strain")
    ax.legend(fontsize=6)
    ax.set_title("Yield strain against pressure\n(lines: from the last elastic rung)")
    save(fig, out, "yield_pressure", ctx)


# Calibrated laws over the DEM (docs/calibration.md "Model envelopes beside the DEM"): per
# amplitude and quantity one figure, one panel per state, with the DEM points (the probe
# method the claims use: dynamic, else minimisation, else the linear response at elastic
# amplitude), the DEM fit, and every calibrated law's envelope for the same probes; and the
# path with every law's prediction. The SVG description lists the laws drawn.
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


def dem_envelope(state_group, kind, probes_only=False):
    """The DEM envelope a panel shows: dynamic, else minimisation, else (elastic only, unless
    probes_only) the linear response; returns (name, group) or None."""
    envs = envelopes(state_group, kind)
    for method in ("dynamic", "minimisation", "linear_response"):
        if method == "linear_response" and (kind != "elastic" or probes_only):
            continue
        for name, g in envs:
            if attr(g, "method") == method:
                return name, g
    return None


def closed(theta, pts):
    order = np.argsort(theta)
    p = np.asarray(pts)[order]
    return np.vstack([p, p[:1]])


def fig_model_envelopes(f, out, ctx, kind, quantity):
    models = calibrated_models(f)
    if not models:
        ctx["notes"].append(f"models {kind} {quantity}: no calibrated law")
        return
    k_star = float(attr(f["material"], "k_star", 1.0)) if "material" in f else 1.0
    panels = []
    for eps, label, g in states(f):
        env = dem_envelope(g, kind)
        if env is not None:
            panels.append((eps, label, env))
    if not panels:
        ctx["notes"].append(f"models {kind} {quantity}: no {kind} DEM envelopes")
        return
    key = "stress_star" if quantity == "stress" else "fabric"
    fit_key = "fit_stress" if quantity == "stress" else "fit_fabric"
    sym = "\\sigma^*" if quantity == "stress" else "F"
    e = power_of_ten(*(finite(g, key) for _, _, (_, g) in panels))
    scale = 10.0 ** e
    fig, axes, leg = panel_grid(len(panels))
    ncols = fig.axes[0].get_subplotspec().get_gridspec().ncols
    drawn, no_fabric, handles = set(), set(), {}
    for k, (ax, (eps, label, (name, g))) in enumerate(zip(axes, panels)):
        r = finite(g, key) / scale
        ax.plot(r[:, 0], r[:, 1], "k.", ms=4, zorder=4)
        handles.setdefault("dem", Line2D([], [], ls="none", marker=".", color="k", ms=4,
                                         label=f"DEM ({attr(g, 'method', '?')})"))
        fit = g.get(fit_key)
        if fit_ok(fit):
            x, y = fit_curve(fit)
            ax.plot(x / scale, y / scale, "k-", lw=0.8, zorder=3)
            shape = attr(fit, "shape")
            handles.setdefault("fit " + shape, Line2D([], [], color="k", lw=0.8,
                                                      label=f"DEM fit: {shape}"))
        for i, (mname, mg, mlabel) in enumerate(models):
            path = f"states/{label}/envelopes/{name}"
            if path not in mg:
                continue
            em = mg[path]
            if quantity == "fabric":
                pred = em["fabric"][:]
            elif "stress_star" in em:  # rendulic/2: starred like the DEM's
                pred = em["stress_star"][:]
            else:  # rendulic/1 stored the law's envelope in Pa
                pred = em["stress"][:] / k_star
            if quantity == "fabric" and not np.any(pred):
                no_fabric.add(mname)  # a law without fabric (hypoplastic_wu): nothing to draw
                continue
            c = closed(em["theta_deg"][:], pred) / scale
            colour = MODEL_COLOURS[i % len(MODEL_COLOURS)]
            ax.plot(c[:, 0], c[:, 1], "-", color=colour, lw=1.1, zorder=2)
            handles.setdefault("m " + mname, Line2D([], [], color=colour, lw=1.1, label=mlabel))
            drawn.add(mname)
        rendulic_axes(ax, [r[:, 0]], [r[:, 1]], label)
        rendulic_labels(ax, sym, e, k % ncols == 0)
        ax.set_title(state_title(label, eps))
    legend_in(leg, list(handles.values()))
    amps = sorted({float(attr(g, "amplitude", 0)) for _, _, (_, g) in panels})
    title = (f"Calibrated laws over the DEM: {kind} {quantity} envelopes, |δε| = "
             + ", ".join(f"{a:g}" for a in amps))
    if no_fabric:
        title += "\n(no fabric predicted by " + ", ".join(sorted(no_fabric)) + ")"
    fig.suptitle(title)
    fig.tight_layout()
    desc = "models: " + ", ".join(sorted(drawn))
    if no_fabric:
        desc += "; no fabric: " + ", ".join(sorted(no_fabric))
    save(fig, out, f"models_{kind}_{quantity}", ctx, description=desc)


def fig_models_path(f, out, ctx):
    models = [m for m in calibrated_models(f) if "path" in m[1]]
    if "path" not in f or not models:
        ctx["notes"].append("models path: no path or no law with a predicted path")
        return
    g = f["path"]
    k_star = float(attr(f["material"], "k_star", 1.0)) if "material" in f else 1.0
    x = -finite(g, "eps_dev")
    e0 = -x[0]
    s, F = finite(g, "stress_star"), finite(g, "fabric")
    es = power_of_ten(s[:, 0, 0], s[:, 1, 1])
    fig, ax = plt.subplots(1, 2, figsize=(PAGE_WIDTH, 3.2))
    for i, lab in ((0, "xx"), (1, "yy")):
        ax[0].plot(x, s[:, i, i] / 10.0 ** es, "k-" if i == 0 else "k--", lw=1.4,
                   label=rf"DEM $\sigma^*_{{{lab}}}$")
        ax[1].plot(x, F[:, i, i], "k-" if i == 0 else "k--", lw=1.4, label=f"DEM $F_{{{lab}}}$")
    drawn = []
    for j, (mname, mg, mlabel) in enumerate(models):
        p = mg["path"]
        xm = -(e0 + p["eps_dev"][:])
        sm, fm = p["stress"][:] / k_star / 10.0 ** es, p["fabric"][:]
        c = MODEL_COLOURS[j % len(MODEL_COLOURS)]
        for i in (0, 1):
            ls = "-" if i == 0 else "--"
            ax[0].plot(xm, sm[:, i, i], ls, color=c, lw=1, label=mlabel if i == 0 else None)
            ax[1].plot(xm, fm[:, i, i], ls, color=c, lw=1, label=mlabel if i == 0 else None)
        drawn.append(mname)
    # The DEM sets the scale: a law far off leaves the frame rather than flatten the data.
    for a, d in ((ax[0], s / 10.0 ** es), (ax[1], F)):
        lo = min(d[:, 0, 0].min(), d[:, 1, 1].min())
        hi = max(d[:, 0, 0].max(), d[:, 1, 1].max())
        a.set_ylim(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo))
    for a in ax:
        a.set_xlabel(r"$-\varepsilon_{dev}$")
    # One legend below both panels (inside, it would hide the curves): a colour per source,
    # the line style (xx solid, yy dashed) is in the titles.
    handles = [Line2D([], [], color="k", lw=1.4, label="DEM")]
    handles += [Line2D([], [], color=MODEL_COLOURS[j % len(MODEL_COLOURS)], lw=1, label=m[2])
                for j, m in enumerate(models)]
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
               ncol=min(len(handles), 3))
    ax[0].set_ylabel(with_power(r"stress $\sigma^*_{ii}$", es))
    ax[1].set_ylabel(r"fabric $F_{ii}$")
    ax[0].set_title("(a) stress: xx solid, yy dashed")
    ax[1].set_title("(b) fabric: xx solid, yy dashed")
    fig.suptitle("Calibrated laws along the main path (Fig. 1 analogue)")
    fig.tight_layout()
    save(fig, out, "models_path", ctx, description="models: " + ", ".join(sorted(drawn)))


# --- sweep files ----------------------------------------------------------------------------
FACTOR_STYLE = {"dt_factor": ("o", "tab:blue"), "dt_factor_tight": ("o", "tab:cyan"),
                "n_particles": ("s", "tab:green"), "inertial_number": ("^", "tab:orange"),
                "relax": ("D", "tab:purple"), "method": ("*", "tab:red")}
METHOD_MARKER = {"dynamic": "*", "minimisation": "P", "linear_response": "X"}
ERROR_FLOOR = 1e-6  # the reference itself has error 0: drawn on the floor
LABEL_GID = "point-label"  # gid of the value labels placed by place_labels


def overlap(a, b):
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return w * h if w > 0 and h > 0 else 0.0


def place_labels(ax, items, fontsize=6):
    """Labels (x, y, text, colour) beside their points without overlapping each other, the
    points or the axes frame: each takes the first free place on rings of growing radius
    around its point (beyond the first ring with a leader line). A label with no free place
    is left out and returned, so the caller can list it instead of drawing it over another."""
    fig = ax.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    pts = [ax.transData.transform((x, y)) for x, y, _, _ in items]
    r_px = 4.0 * fig.dpi / 72.0
    taken = [mtransforms.Bbox([[px - r_px, py - r_px], [px + r_px, py + r_px]])
             for px, py in pts]
    frame = ax.get_window_extent(renderer)
    left_out = []
    directions = [(1, 1), (1, -1), (-1, 1), (-1, -1), (0, 1), (0, -1), (1, 0), (-1, 0)]
    for (x, y, text, colour) in items:
        placed = False
        for radius in (4, 11, 18, 26, 36, 48):
            for dx, dy in directions:
                ha = "left" if dx > 0 else "right" if dx < 0 else "center"
                va = "bottom" if dy > 0 else "top" if dy < 0 else "center"
                arrow = dict(arrowstyle="-", color=colour, lw=0.4) if radius > 4 else None
                t = ax.annotate(text, (x, y), xytext=(dx * radius, dy * radius),
                                textcoords="offset points", ha=ha, va=va, fontsize=fontsize,
                                color=colour, arrowprops=arrow, annotation_clip=False)
                bb = t.get_window_extent(renderer)
                inside = (bb.x0 >= frame.x0 and bb.x1 <= frame.x1 and bb.y0 >= frame.y0 and
                          bb.y1 <= frame.y1)
                if inside and all(overlap(bb, o) == 0.0 for o in taken):
                    t.set_gid(LABEL_GID)
                    taken.append(bb)
                    placed = True
                    break
                t.remove()
            if placed:
                break
        if not placed:
            left_out.append(text)
    return left_out


def readable_log_axes(ax):
    """A log axis spanning less than a decade gets a few plain ticks (the default labels every
    minor tick in scientific notation, and they run into each other)."""
    for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
        if axis.get_scale() == "log" and lo > 0 and hi / lo < 10:
            axis.set_major_locator(MaxNLocator(5))
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_locator(NullLocator())


def draw_sweep_points(ax, rows):
    """One marker and colour per factor (per method for the method points), value labels;
    filled markers meet the accuracy target. Returns the labels, to be placed once the axes
    are final."""
    labels = []
    for factor, (marker, colour) in FACTOR_STYLE.items():
        pts = [r for r in rows if r["factor"] == factor]
        if not pts:
            continue
        for r in pts:
            err = max(float(r["error"]), ERROR_FLOOR)
            m = METHOD_MARKER[r["method"]] if factor == "method" else marker
            ax.plot(float(r["cpu_s"]), err, m, color=colour, ms=7 if factor == "method" else 5,
                    mfc=colour if int(r["meets_target"]) else "none")
            label = r["method"] if factor == "method" else f"{float(r['value']):g}"
            labels.append((float(r["cpu_s"]), err, label, colour))
        ax.plot([], [], marker, color=colour, label=factor)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU time of the envelope [s]")
    return labels


def fig_pareto(f, out, ctx):
    """Speed versus accuracy (rendulic sweep): envelope error against CPU time, log-log."""
    g = f["sweep"]
    if "points" not in g:
        ctx["notes"].append("Pareto chart: no probe-method points (path_rate only)")
        return
    rows = []
    for name in sorted(g["points"]):
        p = g["points"][name]
        rows.append({k: attr(p, k) for k in p.attrs})
    ok = [r for r in rows if r["status"] == "ok" and r["envelope"] == "elastic"]
    if not ok:
        ctx["notes"].append("Pareto chart: no elastic point with status ok")
        return
    plastic = [r for r in rows if r["status"] == "ok" and r["envelope"] == "plastic"]
    fig, axes = plt.subplots(2 if plastic else 1, 1,
                             figsize=(PAGE_WIDTH, 9.0 if plastic else 4.8), squeeze=False)
    ax = axes[0][0]
    labels = draw_sweep_points(ax, ok)
    front = sorted((float(r["cpu_s"]), max(float(r["error"]), ERROR_FLOOR))
                   for r in ok if r["pareto"])
    if front:
        ax.step([x for x, _ in front], [y for _, y in front], where="post", color="0.4",
                lw=1, ls="--", label="Pareto front")
    target = float(attr(g, "target"))
    ax.axhline(target, color="tab:red", lw=0.8, ls=":", label=f"target {target:g}")
    ax.set_ylabel(r"max$_\theta$ $|\delta\sigma^* - \delta\sigma^*_{ref}|$ / $a_{ref}$")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title("(a) elastic envelope against the linear response (filled: meets the target; "
                 f"the reference itself at {ERROR_FLOOR:g})")
    # Headroom for the labels of the highest and lowest points.
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo / 3, hi * 3)
    panels = [(ax, labels)]
    if plastic:
        bx = axes[1][0]
        panels.append((bx, draw_sweep_points(bx, plastic)))
        bx.set_ylabel("error against the minimisation envelope")
        bx.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
        bx.set_title("(b) elasto-plastic envelope, |δε| = "
                     f"{float(attr(g, 'plastic_amplitude')):g}")
        lo, hi = bx.get_ylim()
        bx.set_ylim(lo / 3, hi * 3)
    for a, _ in panels:
        readable_log_axes(a)
    fig.tight_layout()
    unlabelled = []
    for a, lab in panels:
        unlabelled += place_labels(a, lab)
    # Settings that could not run and the sweep's findings: full text, wrapped, below.
    notes = [f"{r['factor']} = {float(r['value']):g}: {r['status']}"
             for r in rows if r["status"] != "ok"]
    notes += attr_list(g, "breaks", sep="\n")
    if unlabelled:
        notes.append("unlabelled (no free place): " + ", ".join(unlabelled))
    if notes:
        text = "\n".join(textwrap.fill(n, 130, subsequent_indent="    ") for n in notes)
        fig.text(0.0, 0.0, text, fontsize=6, va="top", ha="left",
                 transform=fig.transFigure)
    save(fig, out, "pareto", ctx)


def fig_path_rate(f, out, ctx):
    """The path's rate (rendulic sweep, factor path_rate): the steady-state stress ratio
    against the inertial number, each seed and their mean with its standard error."""
    g = f["sweep"]
    if "path_rate" not in g:
        return
    rows = [g["path_rate"][k] for k in sorted(g["path_rate"])]
    ok = [r for r in rows if attr(r, "status") == "ok"]
    if not ok:
        ctx["notes"].append("path rate: no point with status ok")
        return
    fig, ax = plt.subplots(figsize=(4.6, 3.4))
    labels = []
    for r in ok:
        i = float(attr(r, "inertial_number"))
        seeds = np.atleast_1d(np.asarray(attr(r, "ratio_per_seed", []), dtype=float))
        ax.plot([i] * len(seeds), seeds, ".", color="0.6", ms=4)
        filled = int(attr(r, "converged", 0)) == 1
        ax.errorbar(i, float(attr(r, "ratio")), yerr=float(attr(r, "ratio_stderr")), fmt="o",
                    color="tab:blue", mfc="tab:blue" if filled else "white", capsize=3)
        labels.append((i, float(attr(r, "ratio")), f"{float(attr(r, 'rate')):g}/s", "0.2"))
    ax.set_xscale("log")
    ax.set_xlabel("inertial number of the path (steady state)")
    ax.set_ylabel(r"steady-state $|\sigma_{dev}|/P$")
    target = float(attr(g, "path_rate_target", 0.02))
    ax.set_title("Path rate: mean ± standard error over seeds (grey: each seed);\nfilled: "
                 f"within {100 * target:g} % of the run 4x slower")
    readable_log_axes(ax)
    fig.tight_layout()
    place_labels(ax, labels)
    save(fig, out, "path_rate", ctx)


# --- driver ---------------------------------------------------------------------------------
def figure_list(f, out, ctx):
    if "sweep" in f:  # a sweep file (rendulic sweep): the Pareto and path-rate charts
        return [("Pareto chart", lambda: fig_pareto(f, out, ctx)),
                ("path rate", lambda: fig_path_rate(f, out, ctx))]
    return [
        ("isotropic branch", lambda: fig_isotropic(f, out, ctx)),
        ("Fig. 1", lambda: fig1_path(f, out, ctx)),
        ("Fig. 2", lambda: fig2_strain_circle(f, out, ctx)),
        ("Fig. 3", lambda: fig_envelopes(f, out, ctx, 3, "elastic", "stress")),
        ("Fig. 4", lambda: fig_envelopes(f, out, ctx, 4, "elastic", "fabric")),
        ("Fig. 5", lambda: fig_envelopes(f, out, ctx, 5, "plastic", "stress")),
        ("Fig. 6", lambda: fig_envelopes(f, out, ctx, 6, "plastic", "fabric")),
        ("Fig. 7", lambda: fig7_trends(f, out, ctx)),
        ("elastic range", lambda: fig_elastic_range(f, out, ctx)),
        ("yield against P*", lambda: fig_yield_pressure(f, out, ctx)),
        ("models elastic stress", lambda: fig_model_envelopes(f, out, ctx, "elastic", "stress")),
        ("models plastic stress", lambda: fig_model_envelopes(f, out, ctx, "plastic", "stress")),
        ("models elastic fabric", lambda: fig_model_envelopes(f, out, ctx, "elastic", "fabric")),
        ("models plastic fabric", lambda: fig_model_envelopes(f, out, ctx, "plastic", "fabric")),
        ("models path", lambda: fig_models_path(f, out, ctx)),
    ]


def draw_all(path, out, keep=False, jobs=1):
    """Draws every figure of results file `path` into folder `out`. Returns (files written,
    notes on skipped figures, {name: Figure} when keep, else {}): keep leaves the figures open
    for a caller that inspects them. jobs > 1 draws the figures in that many processes (each
    figure is independent; the lists come back in figure order either way)."""
    os.makedirs(out, exist_ok=True)
    if keep or jobs <= 1:
        drawn, kept = draw_figures(path, out, None, keep)
    else:
        with h5py.File(path, "r") as f:
            count = len(figure_list(f, out, {}))
        drawn, kept = draw_forked(path, out, count, min(jobs, count)), {}
    return [w for _, ws, _ in drawn for w in ws], [n for _, _, ns in drawn for n in ns], kept


def fork_with_pipe():
    """(pid as os.fork returns it, read end, write end) of a pipe and a forked process, or None
    when there is no pipe or no process to spare (a pipe made for a fork that failed is closed
    again)."""
    try:
        r, w = os.pipe()
    except OSError:
        return None
    try:
        return os.fork(), r, w
    except OSError:
        os.close(r)
        os.close(w)
        return None


def draw_forked(path, out, count, jobs):
    """draw_all's figures in `jobs` processes: the figures' numbers wait in a pipe, and this
    process and each forked child take the next one whenever they are free, so that no
    process idles while another still has several figures to draw (quick.toml's figures take
    0.3-1.2 s each; dealt out in turns, one process drew 5.6 s of them and the other 4.4 s).
    Each child sends its lists back through a pipe of its own. Stopped (rendulic sends SIGTERM
    when it is stopped itself), this process kills and reaps its children before it exits, and
    a child dies with this process in any case: none draws on.
    Returns [(i, files written, notes)] in figure order."""
    import json
    import signal

    children = []  # (pid, read end of its pipe, k)
    # Two bytes per figure number, all written before any process reads: a read of two bytes
    # from a pipe takes one whole number, whichever process makes it, and the closed write end
    # makes an empty read once the numbers are gone. A process that cannot be forked leaves
    # its figures to the others.
    queue, w = os.pipe()
    os.write(w, b"".join(i.to_bytes(2, "little") for i in range(count)))
    os.close(w)

    def numbers():
        while len(taken := os.read(queue, 2)) == 2:
            yield int.from_bytes(taken, "little")

    def end_children():
        # A child killed while it saves leaves its temporary (save()); it is removed here.
        for pid, _, _ in children:
            try:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
            except OSError:
                pass
        remove_temporaries(out, [pid for pid, _, _ in children])

    def stop(*_):
        end_children()
        remove_temporaries(out, [os.getpid()])  # this process's own, interrupted
        os._exit(128 + signal.SIGTERM)

    def share():
        return draw_figures(path, out, numbers(), False)[0]

    previous = signal.signal(signal.SIGTERM, stop)
    parent = os.getpid()
    for k in range(1, jobs):
        # A stop between the fork and the child's entry in `children` would leave that child
        # to draw on: the signal waits until the entry is made (and the child, until it will die
        # with this process).
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
        forked = fork_with_pipe()
        if forked is None:  # no process (or pipe) to spare: the others draw its figures
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
            continue
        pid, r, w = forked
        if pid == 0:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            try:  # PR_SET_PDEATHSIG: killed with this process, whatever kills it; and
                # PR_SET_NAME: shown as rendulic-draw by ps and top (and found so by the tests)
                import ctypes
                libc = ctypes.CDLL(None)
                libc.prctl(1, int(signal.SIGKILL))
                libc.prctl(15, b"rendulic-draw", 0, 0, 0)
            except (OSError, AttributeError):
                pass
            if os.getppid() != parent:  # it died before the line above took effect
                os._exit(1)
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
            os.close(r)
            try:
                data = json.dumps({"figures": share()})
            except BaseException as e:  # noqa: BLE001  reported by the parent in one line
                data = json.dumps({"error": f"{type(e).__name__}: {e}"})
            with os.fdopen(w, "w") as f:
                f.write(data)
            os._exit(0)
        os.close(w)
        children.append((pid, r, k))
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
    try:
        figures = share()
    except BaseException:
        # This process failed (a full disk): its children would die with it mid-figure.
        end_children()
        raise
    os.close(queue)
    errors = []
    for pid, r, k in children:
        with os.fdopen(r, "r") as f:
            data = f.read()
        os.waitpid(pid, 0)
        got = json.loads(data) if data else {"error": f"drawing process {k} ended without a word"}
        if "error" in got:
            errors.append(got["error"])
        else:
            figures += [tuple(x) for x in got["figures"]]
    children.clear()
    signal.signal(signal.SIGTERM, previous)
    if errors:
        raise RuntimeError(errors[0])
    return sorted(figures, key=lambda x: x[0])


def remove_temporaries(out, pids):
    """Removes the temporaries save() made in `out` for the processes `pids`."""
    ends = tuple(f".tmp-{pid}" for pid in pids)
    try:
        names = os.listdir(out)
    except OSError:
        return
    for name in names:
        if name.startswith(".") and name.endswith(ends):
            try:
                os.remove(os.path.join(out, name))
            except OSError:
                pass


def draw_figures(path, out, which, keep):
    """Draws the figures of figure_list numbered in `which` (None: all; any iterable, taken
    one number at a time once the file is open), with the file opened once.
    Returns ([(i, files written, notes) per figure], {name: Figure} when keep, else {})."""
    drawn = []
    ctx = {"written": [], "notes": [], "keep": {} if keep else None}
    with plt.rc_context(STYLE), h5py.File(path, "r") as f:
        figures = figure_list(f, out, ctx)
        for i in range(len(figures)) if which is None else which:
            name, draw = figures[i]
            try:
                draw()
            except (KeyError, ValueError, IndexError, TypeError) as e:  # partial files: skip
                # and say why
                if not keep:
                    plt.close("all")
                ctx["notes"].append(f"{name}: {e}")
            drawn.append((i, ctx["written"], ctx["notes"]))
            ctx["written"], ctx["notes"] = [], []
    return drawn, ctx["keep"] or {}


def plot_jobs():
    """Processes to draw with: RENDULIC_PLOT_JOBS (rendulic passes its thread count), else
    the cores this process may use."""
    env = os.environ.get("RENDULIC_PLOT_JOBS", "")
    if env.strip():
        return max(1, int(env))
    return len(os.sched_getaffinity(0))


def main():
    # rendulic stops this script with SIGTERM: as an exception, so that a figure being saved
    # removes its temporary (draw_forked's own handler does so for its processes).
    import signal
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    if len(sys.argv) != 3:
        print("usage: plot.py FILE.h5 OUTDIR", file=sys.stderr)
        return 2
    written, notes, _ = draw_all(sys.argv[1], sys.argv[2], jobs=plot_jobs())
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
