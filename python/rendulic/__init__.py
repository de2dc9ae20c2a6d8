"""rendulic from Python (docs/python.md).

Results files read into numpy without HDF5 paths (Results), envelope fits (fit_envelope), a
constitutive model's envelope and material-point paths (model_envelope, material_point_path),
probing a packing (probe) and running a scenario (run). Everything goes through the same C++
functions as the `rendulic` command, so the numbers are the CLI's; bad input raises
rendulic.InputError (a ValueError) with the CLI's one-line message. Long calls release the
GIL, report progress to an optional callable progress(stage, task, fraction) and stop on
Ctrl-C (KeyboardInterrupt) or when the callable raises (its exception).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Callable, Optional

import numpy as np

from . import _rendulic
from ._rendulic import InputError, fit_loss_choices, fit_shape_choices, law_names, probe_methods

__all__ = [
    "InputError", "Results", "State", "Envelope", "Fit", "fit_envelope", "model_envelope",
    "material_point_path", "probe", "run", "fit_shape_choices", "fit_loss_choices", "law_names",
    "probe_methods",
]

Progress = Optional[Callable[[str, str, float], Any]]


@dataclass
class Fit:
    """An ellipse, line or circle fit of an envelope (docs/fitting.md); stderr holds the
    standard errors (1 sigma) where defined, covariance is of (cx, cy, a, b, inclination)."""
    shape: str
    center: tuple
    semi_axes: tuple
    inclination_deg: Optional[float]
    rms: float
    stderr: dict
    n_points: int
    loss: str
    loss_scale: float
    converged: bool
    used_theta: bool
    selection: str
    line_p_value: Optional[float]
    covariance: Optional[np.ndarray] = None
    residuals: Optional[np.ndarray] = None
    error: str = ""


def _fit(d: Optional[dict]) -> Optional[Fit]:
    if d is None:
        return None
    if d.get("shape") == "none":
        return Fit("none", (np.nan, np.nan), (np.nan, np.nan), None, np.nan, {}, 0, "", 0.0,
                   False, False, "", None, error=d.get("error", ""))
    return Fit(**d)


@dataclass
class State:
    """A state at rest: positions [N,3] (m), radii [N], cell lengths [3] (m), stress and
    fabric [3,3] (stress in Pa, compression positive), and its attributes."""
    label: str
    stress: np.ndarray
    fabric: np.ndarray
    positions: Optional[np.ndarray]
    radii: Optional[np.ndarray]
    cell_lengths: Optional[np.ndarray]
    attributes: dict

    @property
    def cell(self) -> Optional[np.ndarray]:
        """The periodic cell as a diagonal 3x3 matrix (m)."""
        return None if self.cell_lengths is None else np.diag(self.cell_lengths)


@dataclass
class Envelope:
    """One response envelope (docs/probes.md): per probe direction theta_deg, the pairs in its
    probe plane (the Rendulic pairs, sqrt2 lateral and axial, in the default plane) of strain,
    stress/k* and fabric, the tensors d_stress (Pa)
    and d_fabric [m,3,3], and the stored fits of the stress and fabric pairs."""
    state: str
    name: str
    method: str
    amplitude: float
    k_star: float
    theta_deg: np.ndarray
    strain: np.ndarray
    stress_star: np.ndarray
    fabric: np.ndarray
    d_stress: np.ndarray
    d_fabric: np.ndarray
    d_fabric_split: dict
    diagnostics: dict
    attributes: dict
    fit_stress: Optional[Fit]
    fit_fabric: Optional[Fit]
    stiffness: Optional[np.ndarray] = None
    fabric_stiffness: Optional[np.ndarray] = None
    plane: str = "rendulic"  # the probe plane of the pairs (docs/probes.md "Probe planes")

    @property
    def stress(self) -> np.ndarray:
        """The stress pairs in Pa (stress_star times k*)."""
        return self.stress_star * self.k_star


def _envelope(d: dict) -> Envelope:
    d = dict(d)
    d["fit_stress"] = _fit(d.get("fit_stress"))
    d["fit_fabric"] = _fit(d.get("fit_fabric"))
    return Envelope(**d)


class _TextChecked:
    """The C++ reader, with a name or text of the file that is not UTF-8 raised as InputError
    naming the file and the bytes (pybind11 raised a bare UnicodeDecodeError converting it)."""

    def __init__(self, reader):
        self._reader = reader
        self.path = reader.path

    def __getattr__(self, name):
        method = getattr(self._reader, name)

        def call(*args):
            try:
                return method(*args)
            except UnicodeDecodeError as e:
                raise InputError(f"{self.path}: a name or text in the file is not UTF-8: "
                                 f"{bytes(e.object)!r}") from None
        return call


class Results:
    """A results file (docs/results.md), read through the same reader as the CLI.

    r = Results("out/quick/results.h5"); r.states(); r.state("a").stress; r.file;
    r.envelopes(state="a"); r.fits(state="a"); r.calibration(); r.path(); r.isotropic()
    A pressure branch's states: root=r.branches()[0].
    """

    def __init__(self, path: str | os.PathLike):
        self._r = _TextChecked(_rendulic._Reader(os.fspath(path)))

    @property
    def file(self) -> str:
        """The results file's path."""
        return self._r.path

    def attributes(self, obj: str = "/") -> dict:
        """The attributes of one group or dataset (the file's own names, docs/results.md)."""
        return self._r.attrs(obj)

    @property
    def scenario(self) -> str:
        """The effective scenario of the run (TOML text)."""
        return self._r.attrs("/").get("scenario", "")

    @property
    def material(self) -> dict:
        return self._r.attrs("/material")

    def states(self, root: str = "") -> list[str]:
        return self._r.states(root)

    def state(self, label: str, root: str = "") -> State:
        d = self._r.state(label, root)
        return State(label=label, stress=d["stress"], fabric=d["fabric"],
                     positions=d.get("positions"), radii=d.get("radii"),
                     cell_lengths=d.get("cell_lengths"), attributes=d["attributes"])

    def envelope_names(self, state: str, root: str = "") -> list[str]:
        return self._r.envelopes(state, root)

    def envelope(self, state: str, name: str, root: str = "") -> Envelope:
        return _envelope(self._r.envelope(state, name, root))

    def envelopes(self, state: Optional[str] = None, method: Optional[str] = None,
                  root: str = "") -> list[Envelope]:
        """Every envelope of one state (or of every state), optionally of one method."""
        if method is not None:
            _rendulic.check_probe_method(method)
        out = []
        for s in ([state] if state is not None else self.states(root)):
            for n in self.envelope_names(s, root):
                e = self.envelope(s, n, root)
                if method is None or e.method == method:
                    out.append(e)
        return out

    def fits(self, state: Optional[str] = None, method: Optional[str] = None,
             root: str = "") -> dict:
        """{(state, envelope name): (stress fit, fabric fit)} of the stored fits."""
        return {(e.state, e.name): (e.fit_stress, e.fit_fabric)
                for e in self.envelopes(state, method, root)}

    def isotropic(self) -> dict:
        """The isotropic branch: one array per series (volume_fraction, pressure, ...)."""
        return self._r.series("/isotropic")

    def path(self, root: str = "") -> dict:
        """The undrained path (or a pressure branch's, root=...): arrays per series."""
        return self._r.series(root + "/path")

    def branches(self) -> list[str]:
        """The pressure branches' roots (for root=...)."""
        return self._r.branches()

    def calibration(self) -> dict:
        """The calibrated laws: {"attributes": ..., "models": {name: {"params", "stderr",
        "correlation", "attributes", "states", "path"}}} ({} if the file has none)."""
        return self._r.calibration()


def fit_envelope(points, theta_deg=None, strain=None, amplitude: float = 0.0,
                 shape: str = "auto", loss: str = "none", loss_scale: float = 0.0,
                 use_theta: bool = True) -> Fit:
    """Fits one envelope's response points [n,2] (docs/fitting.md), as `rendulic fit`.

    shape: one of fit_shape_choices() (auto: line unless the ellipse fits significantly
    better); loss: one of fit_loss_choices(); theta_deg: the probe directions, if known."""
    return Fit(**_rendulic.fit_envelope(points, theta_deg, strain, amplitude, shape, loss,
                                        loss_scale, use_theta))


def model_envelope(model: str, state, params=None, amplitude: float = 5e-5,
                   directions: int = 36, method: str = "integrated",
                   scheme: str = "modified-euler", tolerance: float = _rendulic.DEFAULT_TOLERANCE, substeps: int = 1,
                   umat: str = "") -> dict:
    """A law's envelope at a state (docs/models.md), as `rendulic envelope`.

    state: {"stress": 3x3 (Pa), "fabric": 3x3, "volume_fraction": x} or a TOML file; params:
    {name: value} or a TOML file (missing names keep their defaults). Returns theta_deg and
    the Rendulic pairs strain, stress (Pa), fabric, with the tensors and the driver's error."""
    return _rendulic.model_envelope(model, _arg(state, "state", "state"),
                                    _arg(params, "params", "parameters"), amplitude,
                                    directions, method, scheme, tolerance, substeps, umat)


def material_point_path(model: str, state, params=None, kind: str = "undrained",
                        end: float = -0.05, steps: int = 200, scheme: str = "modified-euler",
                        tolerance: float = _rendulic.DEFAULT_TOLERANCE, substeps: int = 1, umat: str = "",
                        progress: Progress = None) -> dict:
    """A law driven along a path from `state` by the error-controlled driver (docs/models.md):
    kind "undrained" (axisymmetric, to signed deviatoric strain `end`; negative is extension),
    "isotropic" (to volumetric strain `end`), "drained" (triaxial: axial strain `end` along x,
    compression positive, the lateral stresses held at the start's; built-in laws only) or
    "proportional" (to the 3x3 strain tensor `end`, compression positive, a UMAT too). Arrays
    strain, stress, fabric [n,3,3], eps_v, eps_dev, volume_fraction [n], the first row the
    start. progress(stage, task, fraction) as for `run`, called after steps ("path", e.g.
    "drained path of hypoplastic_wu"); Ctrl-C or an exception it raises ends the path."""
    return _rendulic.material_point_path(model, _arg(state, "state", "state"),
                                         _arg(params, "params", "parameters"), kind, end, steps,
                                         scheme, tolerance, substeps, umat, progress)


def probe(packing: str | os.PathLike, out: str | os.PathLike, methods=(), amplitudes=(),
          directions: int = 0, label: str = "imported", sets=None, threads: int = 0,
          quiet: bool = False, progress: Progress = None, planes=(),
          leave_saddle: bool = False) -> Results:
    """Probes a packing as `rendulic probe` (docs/interop.md): a LAMMPS data file or dump, or
    "RESULTS.h5:/states/LABEL". planes: probe planes as `--planes` (rendulic, deviatoric,
    meridian_<Lode deg>; docs/probes.md "Probe planes"), empty for the scenario's.
    sets: {key: value} or ["key=value"] scenario overrides. leave_saddle: as `--leave-saddle`
    (docs/probes.md "Replicated packings"). Returns the written results file."""
    return Results(_rendulic.probe(os.fspath(packing), os.fspath(out), label, list(methods),
                                   list(amplitudes), directions, list(planes), sets, threads,
                                   quiet, progress, leave_saddle))


def run(scenario: str | os.PathLike, out: str | os.PathLike, sets=None, threads: int = 0,
        quiet: bool = False, resume: bool = False, progress: Progress = None) -> Results:
    """Runs a scenario as `rendulic run` (docs/usage.md) and returns its results file."""
    return Results(_rendulic.run(os.fspath(scenario), os.fspath(out), sets, threads, quiet,
                                 resume, progress))


def _arg(x, name: str, what: str):
    """A dictionary as it is (its values as arrays of floats), a path as a path. A value that
    is not numbers is an InputError naming its key, as a TOML file's would be ("parameters:
    'K' ..."); numpy's own "could not convert string to float" named none. Neither a dictionary
    nor a path names the argument itself (name)."""
    if x is None or isinstance(x, (str, os.PathLike)):
        return x
    try:
        items = dict(x).items()
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a dict or the path of a TOML file, got "
                        f"{type(x).__name__}") from None
    out = {}
    for k, v in items:
        try:
            out[k] = np.asarray(v, dtype=float)
        except (TypeError, ValueError, OverflowError):
            shown = repr(v) if len(repr(v)) <= 60 else repr(v)[:57] + "..."
            raise InputError(f"{what}: '{k}' must be a number or a 3x3 array of numbers, "
                             f"got {shown}") from None
    return out
