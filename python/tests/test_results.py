"""The module's numbers against the CLI's on the same inputs, and its reader against h5py
(an independent reader of the same file)."""
import json

import h5py
import numpy as np
import pytest

import rendulic
from conftest import cli, cli_error_line


def test_run_equals_cli_run(cli_run, module_run):
    mod, reports = module_run
    ref = rendulic.Results(cli_run)
    assert mod.states() == ref.states() == ["a", "b"]
    for label in ref.states():
        a, b = mod.state(label), ref.state(label)
        for field in ("stress", "fabric", "positions", "radii", "cell_lengths"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
        names = ref.envelope_names(label)
        assert mod.envelope_names(label) == names and names
        for n in names:
            ea, eb = mod.envelope(label, n), ref.envelope(label, n)
            for field in ("theta_deg", "strain", "stress_star", "fabric", "d_stress", "d_fabric"):
                np.testing.assert_array_equal(getattr(ea, field), getattr(eb, field))
            assert ea.fit_stress.semi_axes == eb.fit_stress.semi_axes
    ca, cb = mod.calibration()["models"], ref.calibration()["models"]
    assert ca.keys() == cb.keys() == {"isotropic_elastic"}
    assert ca["isotropic_elastic"]["params"] == cb["isotropic_elastic"]["params"]
    # Progress came to Python, stage by stage, as fractions.
    stages = [s for s, _, _ in reports]
    assert {"prepare", "isotropic", "path", "states", "probes"} <= set(stages)
    assert all(0.0 <= f <= 1.0 for _, _, f in reports)


def test_reader_matches_h5py(cli_run):
    r = rendulic.Results(cli_run)
    with h5py.File(cli_run, "r") as f:
        s = r.state("a")
        np.testing.assert_array_equal(s.positions, f["/states/a/positions"][()])
        assert s.positions.shape == (250, 3) and s.radii.shape == (250,)
        np.testing.assert_array_equal(s.stress, f["/states/a/stress"][()])
        np.testing.assert_array_equal(s.cell, np.diag(f["/states/a/cell_lengths"][()]))
        assert s.attributes["volume_fraction"] == f["/states/a"].attrs["volume_fraction"]
        e = r.envelopes(state="a", method="dynamic")[0]
        g = f[f"/states/a/envelopes/{e.name}"]
        np.testing.assert_array_equal(e.stress_star, g["stress_star"][()])
        assert e.amplitude == g.attrs["amplitude"] and e.method == "dynamic"
        fit = g["fit_stress"].attrs
        assert e.fit_stress.shape == fit["shape"]
        np.testing.assert_array_equal(e.fit_stress.semi_axes, fit["semi_axes"])
        if "semi_axes_stderr" in fit:
            np.testing.assert_array_equal(e.fit_stress.stderr["semi_axes"], fit["semi_axes_stderr"])
        c = r.calibration()["models"]["isotropic_elastic"]
        names = [n.decode() if isinstance(n, bytes) else n
                 for n in f["/calibration/isotropic_elastic"].attrs["param_names"]]
        assert list(c["params"]) == names
        np.testing.assert_array_equal(list(c["params"].values()),
                                      f["/calibration/isotropic_elastic/params"][()])
        np.testing.assert_array_equal(r.path()["eps_dev"], f["/path/eps_dev"][()])


def test_a_mistyped_root_or_label_is_refused_not_read_as_no_data(cli_run):
    # Both gave [] as if the branch or the state held nothing.
    r = rendulic.Results(cli_run)
    assert r.branches() == [] and r.states() == ["a", "b"]
    with pytest.raises(rendulic.InputError,
                       match=r"no pressure branch '/pressure/nu0.7' \(branches: none\)"):
        r.states(root="/pressure/nu0.7")
    with pytest.raises(rendulic.InputError, match=r"no pressure branch 'nu0.7'"):
        r.envelopes(root="nu0.7")
    with pytest.raises(rendulic.InputError, match=r"no state 'zz' \(states: a, b\)"):
        r.envelope_names("zz")
    # A label is one name: '' and 'a/envelopes' are groups of the file, but not states (they
    # were "state '' has no stress").
    for label in ("", "a/envelopes"):
        with pytest.raises(rendulic.InputError, match=rf"no state '{label}' \(states: a, b\)"):
            r.state(label)
    with pytest.raises(rendulic.InputError, match=r": '': no such object \(the root is '/'\)$"):
        r.attributes("")


def test_an_unknown_probe_method_is_refused_in_the_clis_words(cli_run, tmp_path):
    # envelopes(method="dynamc") gave [] as if the run held no envelope of that method.
    assert rendulic.probe_methods() == ["dynamic", "minimisation", "linear_response"]
    with pytest.raises(rendulic.InputError, match=r"^method: 'dynamc' is not one of dynamic, "
                                                  r"minimisation, linear_response$"):
        rendulic.Results(cli_run).envelopes(method="dynamc")
    packing = f"{cli_run}:/states/a"
    with pytest.raises(rendulic.InputError) as e:
        rendulic.probe(packing, tmp_path / "out", methods=["dynamc"], quiet=True)
    # The CLI's line adds where the options are listed, which a Python user has no use for.
    assert str(e.value) + " (see rendulic --help)" == cli_error_line(
        "probe", packing, "--methods", "dynamc", "--out", tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_stored_pairs_are_the_tensors_pairs(cli_run):
    # Rendulic pair of a tensor: (sqrt2 * mean of yy and zz, xx), docs/results.md.
    e = rendulic.Results(cli_run).envelopes(state="a")[0]
    d = e.d_stress / e.k_star
    pairs = np.stack([np.sqrt(2) * 0.5 * (d[:, 1, 1] + d[:, 2, 2]), d[:, 0, 0]], axis=1)
    np.testing.assert_allclose(e.stress_star, pairs, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(e.stress, e.stress_star * e.k_star)


def test_probe_equals_cli_probe(cli_run, tmp_path):
    packing = f"{cli_run}:/states/a"
    cli("probe", packing, "--methods", "linear_response", "--quiet", "--threads", "1",
        "--out", tmp_path / "cli")
    ref = rendulic.Results(tmp_path / "cli" / "results.h5")
    mod = rendulic.probe(packing, tmp_path / "mod", methods=["linear_response"], threads=1,
                         quiet=True)
    assert mod.states() == ref.states() == ["imported"]
    for ea, eb in zip(mod.envelopes(), ref.envelopes(), strict=True):
        np.testing.assert_array_equal(ea.stress_star, eb.stress_star)
        np.testing.assert_array_equal(ea.stiffness, eb.stiffness)
        assert ea.fit_stress.semi_axes == eb.fit_stress.semi_axes
    # The linear response of the state the run stored is the same response.
    run_lr = rendulic.Results(cli_run).envelopes(state="a", method="linear_response")
    for ea, eb in zip(mod.envelopes(), run_lr):
        np.testing.assert_allclose(ea.stress_star, eb.stress_star, rtol=1e-9)


def test_probe_planes_equal_cli_planes(cli_run, tmp_path):
    # True-triaxial probes through the module: the deviatoric plane's linear response, the same
    # as `rendulic probe --planes deviatoric`, its pairs the projections on the plane's basis.
    packing = f"{cli_run}:/states/a"
    cli("probe", packing, "--methods", "linear_response", "--planes", "deviatoric", "--quiet",
        "--threads", "1", "--directions", "8", "--out", tmp_path / "cli")
    ref = rendulic.Results(tmp_path / "cli" / "results.h5")
    mod = rendulic.probe(packing, tmp_path / "mod", methods=["linear_response"], directions=8,
                         planes=["deviatoric"], threads=1, quiet=True)
    envs = mod.envelopes()
    assert envs and all(e.plane == "deviatoric" for e in envs)
    assert all("_deviatoric_" in e.name for e in envs)
    for ea, eb in zip(envs, ref.envelopes(), strict=True):
        np.testing.assert_array_equal(ea.stress_star, eb.stress_star)
    basis = np.asarray(mod.attributes(f"/states/imported/envelopes/{envs[0].name}")["plane_basis"])
    u, v = basis.reshape(2, 3)
    d = np.array([np.diag(t) for t in envs[0].d_stress]) / envs[0].k_star
    np.testing.assert_allclose(envs[0].stress_star, np.stack([d @ u, d @ v], axis=1),
                               rtol=1e-10, atol=1e-15)


def test_fit_equals_cli_fit(cli_run, tmp_path):
    e = rendulic.Results(cli_run).envelopes(state="b", method="dynamic")[0]
    csv = tmp_path / "env.csv"
    with open(csv, "w") as f:
        f.write("x,y,theta_deg\n")
        for (x, y), t in zip(e.stress_star, e.theta_deg):
            f.write(f"{x!r},{y!r},{t!r}\n")
    for shape in rendulic.fit_shape_choices():
        for loss in ("none", "huber"):
            ref = json.loads(cli("fit", "--in", csv, "--shape", shape, "--loss", loss,
                                 "--json").stdout)
            fit = rendulic.fit_envelope(e.stress_star, theta_deg=e.theta_deg, shape=shape,
                                        loss=loss)
            assert fit.shape == ref["shape"] and fit.loss == ref["loss"]
            assert list(fit.center) == ref["center"] and list(fit.semi_axes) == ref["semi_axes"]
            assert fit.inclination_deg == ref["inclination_deg"] and fit.rms == ref["rms"]
            assert {k: list(v) if isinstance(v, tuple) else v for k, v in fit.stderr.items()} \
                == ref["stderr"]
            assert fit.selection == ref["selection"]


def test_fit_recovers_an_exact_ellipse():
    t = np.radians(np.arange(0, 360, 15))
    phi = np.radians(30.0)
    x, y = 3.0 * np.cos(t), 1.0 * np.sin(t)
    pts = np.stack([1.0 + x * np.cos(phi) - y * np.sin(phi),
                    2.0 + x * np.sin(phi) + y * np.cos(phi)], axis=1)
    f = rendulic.fit_envelope(pts, shape="ellipse")
    np.testing.assert_allclose(f.center, (1.0, 2.0), atol=1e-9)
    np.testing.assert_allclose(f.semi_axes, (3.0, 1.0), atol=1e-9)
    assert f.inclination_deg == pytest.approx(30.0, abs=1e-7)
    assert f.rms < 1e-9 and f.covariance.shape == (5, 5)


def test_leave_saddle_leaves_a_minimum_as_it_is(cli_run, tmp_path):
    # A run's state is at a minimum: --leave-saddle finds no negative mode and moves nothing
    # (a saddle left: tests/app/probe_packing_system_test.cpp).
    rendulic.probe(f"{cli_run}:/states/a", tmp_path / "out", methods=["linear_response"],
                   threads=1, quiet=True, leave_saddle=True)
    with h5py.File(tmp_path / "out" / "results.h5", "r") as f, h5py.File(cli_run, "r") as g:
        assert f["/states/imported"].attrs["saddle_negative_modes"] == 0
        assert f["/states/imported"].attrs["saddle_rounds"] == 0
        np.testing.assert_array_equal(f["/states/imported/positions"][()],
                                      g["/states/a/positions"][()])
