"""Model envelopes and material-point paths: the CLI's numbers, and closed forms of the linear
isotropic law (docs/models.md section 1: D = diag(3K, 2G) in the (iso, dev) frame)."""
import json
import locale
import os
import shutil
import subprocess

import numpy as np
import pytest

import rendulic
from conftest import SOURCE, cli

STATE = {"stress": np.diag([1.2e6, 1.0e6, 1.0e6]), "fabric": np.diag([1.1, 1.0, 1.0]),
         "volume_fraction": 0.8}
PARAMS = {"K": 1.0e8, "G": 2.0e7}


def toml(d):
    lines = []
    for k, v in d.items():
        v = np.asarray(v, dtype=float)
        if v.ndim == 0:
            lines.append(f"{k} = {float(v)!r}")
        else:
            lines.append(f"{k} = [" + ", ".join("[" + ", ".join(repr(float(x)) for x in row)
                                               + "]" for row in v) + "]")
    return "\n".join(lines) + "\n"


def test_model_envelope_equals_cli_envelope(tmp_path):
    (tmp_path / "p.toml").write_text(toml(PARAMS))
    (tmp_path / "s.toml").write_text(toml(STATE))
    for model, params in (("isotropic_elastic", PARAMS), ("hypoplastic_wu", None)):
        args = ["envelope", "--model", model, "--state", tmp_path / "s.toml", "--amplitude",
                "1e-4", "--directions", "12", "--json"]
        if params:
            args += ["--params", tmp_path / "p.toml"]
        ref = json.loads(cli(*args).stdout)
        env = rendulic.model_envelope(model, STATE, params, amplitude=1e-4, directions=12)
        assert env["model"] == ref["model"] == model
        np.testing.assert_array_equal(env["theta_deg"], ref["theta_deg"])
        for key in ("strain", "stress", "fabric"):
            np.testing.assert_array_equal(env[key], np.array(ref[key]))
        # A TOML file works as well as a dictionary.
        again = rendulic.model_envelope(model, tmp_path / "s.toml",
                                        tmp_path / "p.toml" if params else None,
                                        amplitude=1e-4, directions=12)
        np.testing.assert_array_equal(again["stress"], env["stress"])


@pytest.fixture
def comma_locale(tmp_path_factory):
    """A locale whose decimal separator is a comma, as a session may set for its figures
    (docs/python.md "Locales"), compiled from Debian's locale sources (package locales) into a
    folder of the test's own; restored afterwards."""
    if not os.path.exists("/usr/share/i18n/locales/de_DE") or not shutil.which("localedef"):
        pytest.skip("no locale sources (Debian package locales): no locale with a decimal comma")
    folder = tmp_path_factory.mktemp("locales")
    subprocess.run(["localedef", "-i", "de_DE", "-f", "UTF-8", str(folder / "de_DE.UTF-8")],
                   check=True, capture_output=True)
    before, path = locale.setlocale(locale.LC_ALL), os.environ.get("LOCPATH")
    os.environ["LOCPATH"] = str(folder)
    try:
        locale.setlocale(locale.LC_ALL, "de_DE.UTF-8")
        assert locale.localeconv()["decimal_point"] == ","
        yield
    finally:
        locale.setlocale(locale.LC_ALL, before)
        if path is None:
            os.environ.pop("LOCPATH", None)
        else:
            os.environ["LOCPATH"] = path


# The parameters and the state reach the library as TOML text: printf wrote "1,2e+06" under
# such a locale and the call was refused ("state:1: ... saw ','").
def test_a_decimal_comma_locale_changes_no_number(comma_locale):
    env = rendulic.model_envelope("isotropic_elastic", STATE, PARAMS, amplitude=1e-4,
                                  directions=12)
    locale.setlocale(locale.LC_NUMERIC, "C")
    ref = rendulic.model_envelope("isotropic_elastic", STATE, PARAMS, amplitude=1e-4,
                                  directions=12)
    for key in ("strain", "stress", "fabric"):
        np.testing.assert_array_equal(env[key], ref[key])


def test_linear_envelope_fit_has_the_closed_form_axes():
    amp = 1e-4
    env = rendulic.model_envelope("isotropic_elastic", STATE, PARAMS, amplitude=amp,
                                  directions=36, method="rate")
    fit = rendulic.fit_envelope(env["stress"], theta_deg=env["theta_deg"], shape="ellipse")
    np.testing.assert_allclose(sorted(fit.semi_axes, reverse=True),
                               (3 * PARAMS["K"] * amp, 2 * PARAMS["G"] * amp), rtol=1e-9)
    # Major axis on the isotropic direction (sqrt2, 1) of the pairs: atan(1/sqrt2) = 35.26 deg.
    assert abs(fit.inclination_deg - np.degrees(np.arctan(1 / np.sqrt(2)))) < 1e-6


def test_paths_of_the_linear_law_have_the_closed_form():
    iso = rendulic.material_point_path("isotropic_elastic", STATE, PARAMS, kind="isotropic",
                                       end=1e-3, steps=10)
    np.testing.assert_allclose(iso["stress"][-1] - iso["stress"][0],
                               PARAMS["K"] * 1e-3 * np.eye(3), rtol=1e-9, atol=1e-6)
    und = rendulic.material_point_path("isotropic_elastic", STATE, PARAMS, kind="undrained",
                                       end=-0.01, steps=20)
    d = und["stress"][-1] - und["stress"][0]
    eps = und["strain"][-1] - und["strain"][0]
    assert abs(np.trace(eps)) < 1e-12  # undrained: constant volume
    np.testing.assert_allclose(d, 2 * PARAMS["G"] * eps, rtol=1e-9, atol=1e-6)
    assert und["stress"].shape == (21, 3, 3)
    assert und["eps_dev"][-1] == pytest.approx(-0.01, rel=1e-12)



def test_a_substep_count_out_of_range_is_named_as_the_argument():
    state = {"stress": -1e5 * np.eye(3), "volume_fraction": 0.64}
    with pytest.raises(rendulic.InputError, match=r"substeps = 0 is out of range \[1, 100000\]"):
        rendulic.model_envelope("isotropic_elastic", state, scheme="explicit", substeps=0)


def test_driver_arguments_that_change_nothing_are_said_to_in_the_arguments_words(capfd):
    # Substeps with an error-controlled scheme, and any driver argument with the rate method,
    # did nothing without a word.
    state = {"stress": -1e5 * np.eye(3), "volume_fraction": 0.64}
    rendulic.model_envelope("isotropic_elastic", state, substeps=7)
    assert "warning: substeps = 7 has no effect" in capfd.readouterr().err
    rendulic.model_envelope("isotropic_elastic", state, method="rate", scheme="explicit")
    assert ("warning: scheme = explicit has no effect: the rate method"
            in capfd.readouterr().err)
    rendulic.model_envelope("isotropic_elastic", state, method="rate")
    assert "no effect" not in capfd.readouterr().err


def test_a_choice_or_tolerance_out_of_range_is_named_as_the_argument():
    # The messages named the CLI's options (--scheme, --method) or the driver's words.
    state = {"stress": -1e5 * np.eye(3), "volume_fraction": 0.64}
    for kwargs, words in [
            (dict(scheme="rk4"), r"^scheme: 'rk4' is not one of modified-euler, explicit, "
                                 r"bogacki-shampine, auto$"),
            (dict(method="foo"), r"^method: 'foo' is not one of integrated, rate$"),
            (dict(tolerance=2.0), r"^tolerance = 2 is out of range \(0, 1\)$")]:
        with pytest.raises(rendulic.InputError, match=words):
            rendulic.model_envelope("isotropic_elastic", state, **kwargs)


def test_an_empty_file_name_is_refused_not_read_as_no_file():
    # params="" took the law's defaults without a word; a path kind that is not there is named.
    state = {"stress": -1e5 * np.eye(3), "volume_fraction": 0.64}
    with pytest.raises(rendulic.InputError, match=r"^params: the file name is empty$"):
        rendulic.model_envelope("isotropic_elastic", state, params="")
    with pytest.raises(rendulic.InputError, match=r"^state: the file name is empty$"):
        rendulic.material_point_path("isotropic_elastic", "")
    with pytest.raises(rendulic.InputError,
                       match=r"^kind: 'triaxial' is not one of undrained, isotropic, drained, "
                             r"proportional$"):
        rendulic.material_point_path("isotropic_elastic", state, kind="triaxial")
    with pytest.raises(rendulic.InputError, match=r"^the name of the results file is empty$"):
        rendulic.Results("")


def test_a_drained_path_holds_the_lateral_stress_young_and_poisson():
    # kind="drained": axial strain along x, sigma_yy = sigma_zz held (docs/models.md "Paths").
    k, g = PARAMS["K"], PARAMS["G"]
    young, poisson = 9 * k * g / (3 * k + g), (3 * k - 2 * g) / (2 * (3 * k + g))
    state = {"stress": 1e6 * np.eye(3), "volume_fraction": 0.64}
    p = rendulic.material_point_path("isotropic_elastic", state, PARAMS, kind="drained",
                                     end=0.002, steps=8)
    ea = p["strain"][:, 0, 0]
    np.testing.assert_allclose(ea, np.linspace(0, 0.002, 9), rtol=0, atol=1e-16)
    np.testing.assert_allclose(p["stress"][:, 0, 0] - 1e6, young * ea, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(p["stress"][:, 1, 1], 1e6, rtol=1e-9)
    np.testing.assert_allclose(p["strain"][:, 2, 2], -poisson * ea, rtol=1e-9, atol=1e-18)
    np.testing.assert_allclose(p["eps_v"], (1 - 2 * poisson) * ea, rtol=1e-9, atol=1e-18)


def test_a_proportional_path_is_hookes_law_for_the_linear_law():
    # kind="proportional": any strain tensor, in equal steps; sigma = sigma0 + lambda tr(E) I
    # + 2 G E for the linear law (lambda = K - 2G/3).
    k, g = PARAMS["K"], PARAMS["G"]
    state = {"stress": 1e6 * np.eye(3), "volume_fraction": 0.64}
    end = np.array([[0.004, 0.001, 0.0], [0.001, -0.002, 0.0005], [0.0, 0.0005, 0.001]])
    p = rendulic.material_point_path("isotropic_elastic", state, PARAMS, kind="proportional",
                                     end=end, steps=5)
    for i, f in enumerate(np.linspace(0, 1, 6)):
        e = f * end
        want = 1e6 * np.eye(3) + (k - 2 * g / 3) * np.trace(e) * np.eye(3) + 2 * g * e
        np.testing.assert_allclose(p["strain"][i], e, rtol=0, atol=1e-16)
        np.testing.assert_allclose(p["stress"][i], want, rtol=1e-9, atol=1e-3)
    for kind, end, words in [
            ("proportional", 0.01, r"^end: the end of a proportional path is a 3x3 strain tensor$"),
            ("proportional", [[0, 1e-3, 0], [0, 0, 0], [0, 0, 0]],
             r"^end: the end strain must be a symmetric 3x3 tensor$"),
            ("undrained", np.eye(3) * 1e-3,
             r"^end: the end strain of kind 'undrained' is a number \(a strain tensor is for "
             r"kind 'proportional'\)$")]:
        with pytest.raises(rendulic.InputError, match=words):
            rendulic.material_point_path("isotropic_elastic", state, kind=kind, end=end)
    # numpy's scalars are numbers.
    assert rendulic.material_point_path("isotropic_elastic", state, kind="drained",
                                        end=np.float64(1e-3), steps=2)["strain"][-1, 0, 0] == 1e-3


def umat_library(name):
    """A UMAT built with the tests (data/umat, docs/umat.md); ctest says where."""
    return os.path.join(os.environ.get("RENDULIC_UMAT_DIR", str(SOURCE / "build" / "umat")),
                        name + ".so")


def test_a_users_umat_from_python_equals_the_built_in_law():
    # The hypoplastic UMAT of data/umat with the built-in law's defaults, as the CLI test does.
    lib = umat_library("hypoplastic_wu")
    assert os.path.exists(lib), lib
    params = SOURCE / "data" / "umat" / "hypoplastic_wu_params.toml"
    state = {"stress": 1e5 * np.eye(3), "volume_fraction": 0.64}
    u = rendulic.model_envelope("umat", state, params, amplitude=1e-4, directions=12,
                                method="rate", umat=lib)
    b = rendulic.model_envelope("hypoplastic_wu", state, amplitude=1e-4, directions=12,
                                method="rate")
    assert u["model"] == "umat"
    np.testing.assert_allclose(u["stress"], b["stress"], rtol=1e-12, atol=1e-12 * 1e5)
    pu = rendulic.material_point_path("umat", state, params, end=-0.01, steps=20, umat=lib)
    pb = rendulic.material_point_path("hypoplastic_wu", state, end=-0.01, steps=20)
    np.testing.assert_allclose(pu["stress"], pb["stress"], rtol=1e-6, atol=1e-6 * 1e5)
    # A proportional path, which a UMAT may follow (a drained one it may not).
    end = np.diag([0.01, -0.004, -0.002])
    pu = rendulic.material_point_path("umat", state, params, kind="proportional", end=end,
                                      steps=20, umat=lib)
    pb = rendulic.material_point_path("hypoplastic_wu", state, kind="proportional", end=end,
                                      steps=20)
    np.testing.assert_allclose(pu["stress"], pb["stress"], rtol=1e-6, atol=1e-6 * 1e5)


def test_umat_arguments_are_named_as_pythons_not_the_clis():
    # The messages said "--umat PATH.so goes with --model umat" to a Python user.
    state = {"stress": -1e5 * np.eye(3), "volume_fraction": 0.64}
    lib = umat_library("hypoplastic_wu")
    params = SOURCE / "data" / "umat" / "hypoplastic_wu_params.toml"
    for f in (rendulic.model_envelope, rendulic.material_point_path):
        for model, kwargs, words in [
                ("umat", {}, r"^model 'umat' needs umat = 'PATH.so' \(the UMAT library\)$"),
                ("isotropic_elastic", dict(umat=lib),
                 r"^umat = '.*hypoplastic_wu.so' goes with model 'umat', not with "
                 r"'isotropic_elastic'$"),
                ("umat", dict(umat=lib),
                 r"^model 'umat' needs params = 'FILE.toml' \(props, nstatv, "),
                # A dictionary failed on its props' length: "'props' must be a number or a 3x3
                # array of numbers".
                ("umat", dict(umat=lib, params={"props": [-101.2, -962.1, -877.7, 1229.2]}),
                 r"^a UMAT's parameters come from a TOML file \(params = 'FILE.toml'\), not a "
                 r"dictionary"),
                ("umat", dict(umat=str(params), params=params),
                 r"hypoplastic_wu_params.toml: cannot load the UMAT library: "),
                ("elastc", {}, r"^model: unknown model 'elastc' \(known: ")]:
            with pytest.raises(rendulic.InputError, match=words) as e:
                f(model, state, **kwargs)
            assert "--" not in str(e.value)
    with pytest.raises(rendulic.InputError,
                       match=r"^drained path of umat: a drained path is for the built-in laws"):
        rendulic.material_point_path("umat", state, params, kind="drained", umat=lib)
    with pytest.raises(TypeError, match=r"^params: expected a dict or the path of a TOML file, "
                                        r"got int$"):
        rendulic.model_envelope("isotropic_elastic", state, 5)
