"""Bad input arrives as rendulic.InputError with the CLI's one-line message; long work stops on
Ctrl-C (KeyboardInterrupt) and when the progress callback raises, leaving no results file."""
import os
import signal
import threading

import numpy as np
import pytest

import rendulic
from conftest import cli_error_line


def message(excinfo):
    return str(excinfo.value)


def test_input_error_is_a_value_error():
    assert issubclass(rendulic.InputError, ValueError)


def test_missing_file_has_the_cli_message(tmp_path):
    missing = tmp_path / "nope.h5"
    with pytest.raises(rendulic.InputError) as e:
        rendulic.Results(missing)
    assert message(e) == cli_error_line("inspect", missing)
    with pytest.raises(rendulic.InputError) as e:
        rendulic.run(tmp_path / "nope.toml", tmp_path / "out")
    assert message(e) == cli_error_line("run", tmp_path / "nope.toml", "--out", tmp_path / "o")


def test_unknown_key_has_the_cli_message(tiny_toml, tmp_path):
    with pytest.raises(rendulic.InputError) as e:
        rendulic.run(tiny_toml, tmp_path / "out", sets={"dem.n_partcles": 100})
    assert message(e) == cli_error_line("run", tiny_toml, "--set", "dem.n_partcles=100",
                                        "--out", tmp_path / "out")
    assert "n_partcles" in message(e)
    assert not (tmp_path / "out" / "results.h5").exists()


def test_out_of_range_value_has_the_cli_message(tiny_toml, tmp_path):
    with pytest.raises(rendulic.InputError) as e:
        rendulic.run(tiny_toml, tmp_path / "out", sets=["dem.n_particles=-5"])
    assert message(e) == cli_error_line("run", tiny_toml, "--set", "dem.n_particles=-5",
                                        "--out", tmp_path / "out")


def test_a_thread_count_out_of_range_is_an_input_error(tiny_toml, cli_run, tmp_path):
    # CLI11 bounds --threads on the command line; from Python a million threads crashed the
    # interpreter inside the OpenMP runtime (exit 139).
    for call in (lambda: rendulic.run(tiny_toml, tmp_path / "out", threads=10**6),
                 lambda: rendulic.probe(f"{cli_run}:/states/a", tmp_path / "out", threads=-1)):
        with pytest.raises(rendulic.InputError, match=r"threads = (1000000|-1) is out of range "
                                                      r"\[0, 4096\] \(0: every core\)"):
            call()
    assert not (tmp_path / "out").exists()


def test_a_count_beyond_32_bits_is_an_input_error_naming_it(tiny_toml, cli_run, tmp_path):
    # pybind refused such an int with a TypeError listing every signature and naming no
    # argument; numpy's integers stay accepted as counts.
    state = {"stress": np.eye(3) * 1e6}
    calls = {
        "directions = 2147483648": lambda: rendulic.model_envelope(
            "isotropic_elastic", state, directions=2**31),
        "substeps = -2147483649": lambda: rendulic.model_envelope(
            "isotropic_elastic", state, substeps=-2**31 - 1),
        "steps = 4294967296": lambda: rendulic.material_point_path(
            "isotropic_elastic", state, steps=2**32),
        "threads = 2147483648": lambda: rendulic.run(tiny_toml, tmp_path / "out", threads=2**31),
        "directions = 8589934592": lambda: rendulic.probe(
            f"{cli_run}:/states/a", tmp_path / "out", directions=2**33),
    }
    for words, call in calls.items():
        with pytest.raises(rendulic.InputError, match="^" + words + " is out of range$"):
            call()
    env = rendulic.model_envelope("isotropic_elastic", state, directions=np.int64(8),
                                  substeps=np.int32(2))
    assert len(env["theta_deg"]) == 8
    assert not (tmp_path / "out").exists()


def test_model_input_errors_have_the_file_readers_messages():
    state = {"stress": np.eye(3) * 1e6}
    with pytest.raises(rendulic.InputError, match=r"unknown parameter 'Kx' of isotropic_elastic "
                                                  r"\(known: K, G, "):
        rendulic.model_envelope("isotropic_elastic", state, {"Kx": 1.0})
    with pytest.raises(rendulic.InputError, match="parameter 'K' = -1 is outside its bounds"):
        rendulic.model_envelope("isotropic_elastic", state, {"K": -1.0})
    with pytest.raises(rendulic.InputError, match="unknown model 'elastc'"):
        rendulic.model_envelope("elastc", state)
    with pytest.raises(rendulic.InputError, match="must be a symmetric 3x3 tensor"):
        rendulic.model_envelope("isotropic_elastic", {"stress": [[1, 2, 0], [0, 1, 0],
                                                                  [0, 0, 1]]})
    # A fabric is a second moment of contact normals: diag(-1, 0.5, 0.5) failed every probe
    # with "law too stiff or undefined".
    with pytest.raises(rendulic.InputError,
                       match=r"^state: key 'fabric' must be positive semi-definite \(a second "
                             r"moment of contact normals\), got eigenvalues -1, 0.5, 0.5$"):
        rendulic.model_envelope("isotropic_elastic", dict(state, fabric=np.diag([-1, 0.5, 0.5])))
    # A value that is not numbers names its key (numpy's own message named none).
    with pytest.raises(rendulic.InputError, match="parameters: 'K' must be a number"):
        rendulic.model_envelope("isotropic_elastic", state, {"K": "stiff"})
    with pytest.raises(rendulic.InputError, match="state: 'fabric' must be a number"):
        rendulic.material_point_path("isotropic_elastic", dict(state, fabric="isotropic"))
    # An array of numbers of another shape names its key too, with the shape.
    with pytest.raises(rendulic.InputError,
                       match=r"^state: 'fabric' must be a number or a 3x3 array of numbers, "
                             r"got an array of shape \(3,\)$"):
        rendulic.model_envelope("isotropic_elastic", dict(state, fabric=[1, 2, 3]))
    with pytest.raises(rendulic.InputError,
                       match=r"^parameters: 'K' must be a number or a 3x3 array of numbers, "
                             r"got an array of shape \(2, 2, 2\)$"):
        rendulic.model_envelope("isotropic_elastic", state, {"K": np.ones((2, 2, 2))})
    with pytest.raises(TypeError, match="state: expected a dict or the path of a TOML file"):
        rendulic.model_envelope("isotropic_elastic", 5)
    with pytest.raises(rendulic.InputError, match="unknown shape"):
        rendulic.fit_envelope(np.ones((6, 2)), shape="ellipsoid")
    # The fit's own checks, as `rendulic fit` has them: a NaN scale read "must be >= 0".
    for scale in (float("nan"), float("inf"), -1.0):
        with pytest.raises(rendulic.InputError,
                           match=r"^fit: loss_scale must be finite and >= 0 \(0: automatic\)$"):
            rendulic.fit_envelope(np.ones((6, 2)), loss="huber", loss_scale=scale)
    # A path's end that is not finite is refused before its first step.
    with pytest.raises(rendulic.InputError,
                       match=r"^undrained path of isotropic_elastic: the path's end strain is not "
                             r"finite$"):
        rendulic.material_point_path("isotropic_elastic", state, end=float("nan"))


def test_odd_keys_and_argument_types_are_named_not_misread(tiny_toml, tmp_path):
    state = {"stress": np.eye(3) * 1e6}
    # A key was written into the TOML text unquoted: this one set K and G without a word.
    with pytest.raises(rendulic.InputError, match="unknown parameter 'K\" = 5e7"):
        rendulic.model_envelope("isotropic_elastic", state, {'K" = 5e7\n"G': 1e8})
    # numpy's integers are numbers (json knew no np.int64); a text is not a list of settings.
    with pytest.raises(rendulic.InputError, match="dem.n_particles=10: .*out of range"):
        rendulic.run(tiny_toml, tmp_path / "out", sets={"dem.n_particles": np.int64(10)})
    for sets in ("dem.n_particles=100", [1, 2]):
        with pytest.raises(TypeError, match="sets: expected a dict"):
            rendulic.run(tiny_toml, tmp_path / "out", sets=sets)
    with pytest.raises(TypeError, match="sets: the value of 'dem.seed' is not a number"):
        rendulic.run(tiny_toml, tmp_path / "out", sets={"dem.seed": object()})
    with pytest.raises(rendulic.InputError, match="theta_deg: expected a sequence of numbers"):
        rendulic.fit_envelope(np.ones((8, 2)), theta_deg="abc")
    with pytest.raises(rendulic.InputError, match="'volume_fraction' must be a number"):
        rendulic.material_point_path("isotropic_elastic", dict(state, volume_fraction=10**400))
    assert not (tmp_path / "out").exists()


def test_progress_callback_raising_stops_the_run(tiny_toml, tmp_path):
    calls = []

    def progress(stage, task, fraction):
        calls.append(stage)
        raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        rendulic.run(tiny_toml, tmp_path / "out", threads=1, quiet=True, progress=progress)
    assert calls == ["prepare"]  # the first report stopped it
    assert not (tmp_path / "out" / "results.h5").exists()


def test_ctrl_c_stops_the_run(tiny_toml, tmp_path):
    calls = []

    def progress(stage, task, fraction):
        calls.append(stage)
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        rendulic.run(tiny_toml, tmp_path / "out", threads=1, quiet=True, progress=progress)
    assert calls == ["prepare"]
    assert not (tmp_path / "out" / "results.h5").exists()


def test_sigint_from_another_thread_stops_the_run(tiny_toml, tmp_path):
    # SIGINT arrives while the C++ work runs with the GIL released: it is seen at the next
    # progress report (PyErr_CheckSignals). The signal is sent once the run has started.
    started = threading.Event()
    seen = []

    def progress(stage, task, fraction):
        seen.append(stage)
        if not started.is_set():
            started.set()
            threading.Thread(target=os.kill, args=(os.getpid(), signal.SIGINT)).start()

    with pytest.raises(KeyboardInterrupt):
        rendulic.run(tiny_toml, tmp_path / "out", threads=1, quiet=True, progress=progress)
    assert not (tmp_path / "out" / "results.h5").exists()
    # And the next call runs normally (the stop request does not linger).
    env = rendulic.model_envelope("isotropic_elastic", {"stress": np.eye(3) * 1e6})
    assert env["stress"].shape == (36, 2)


# elastoplastic_fabric far below its stress scale: a drained path of minutes (docs/models.md
# "Paths"), 350 s for 100 steps at 1e5 Pa; it could be neither followed nor stopped.
SLOW_PATH = dict(model="elastoplastic_fabric", kind="drained", end=0.1, steps=100,
                 state={"stress": 1e6 * np.eye(3), "volume_fraction": 0.64,
                        "fabric": np.eye(3) / 3})


def test_a_long_material_point_path_reports_and_stops_on_its_callback():
    seen = []

    def progress(stage, task, fraction):
        seen.append((stage, task, fraction))
        raise LookupError("stop the path")

    with pytest.raises(LookupError, match="stop the path"):
        rendulic.material_point_path(progress=progress, **SLOW_PATH)
    assert seen == [("path", "drained path of elastoplastic_fabric", 0.01)]
    # A path that runs through reports its end.
    seen.clear()
    rendulic.material_point_path("isotropic_elastic", SLOW_PATH["state"], kind="drained",
                                 end=0.01, steps=10, progress=lambda *a: seen.append(a))
    assert seen[-1] == ("path", "drained path of isotropic_elastic", 1.0)


def test_ctrl_c_stops_a_long_material_point_path():
    # SIGINT from another thread once the path has started, seen at its next step.
    started = threading.Event()

    def progress(stage, task, fraction):
        if not started.is_set():
            started.set()
            threading.Thread(target=os.kill, args=(os.getpid(), signal.SIGINT)).start()

    with pytest.raises(KeyboardInterrupt):
        rendulic.material_point_path(progress=progress, **SLOW_PATH)


def test_callback_raising_during_the_probes_stops_them(cli_run, tmp_path):
    # Raised from a report made while the probes run (inside their parallel loop): the
    # remaining probes are skipped (ProbeOptions::stop) and the exception comes back.
    seen = []

    def progress(stage, task, fraction):
        seen.append((stage, task, fraction))
        if stage == "probes" and task == "dynamic":
            raise LookupError("stop the probes")

    with pytest.raises(LookupError, match="stop the probes"):
        rendulic.probe(f"{cli_run}:/states/a", tmp_path / "out", methods=["dynamic"],
                       directions=16, threads=1, quiet=True, progress=progress)
    assert seen[-1][:2] == ("probes", "dynamic") and seen[-1][2] < 1.0
    assert not (tmp_path / "out" / "results.h5").exists()


def test_a_progress_callback_cannot_start_another_run(tiny_toml, tmp_path):
    # A nested call ended by clearing the process's progress observer and stop flag: the outer
    # run then went on without its callback and without Ctrl-C, and wrote its results.
    errors = []

    def progress(stage, task, fraction):
        if not errors:
            try:
                rendulic.run(tiny_toml, tmp_path / "inner", threads=1, quiet=True)
            except RuntimeError as e:
                errors.append(str(e))
        elif stage == "states":
            raise LookupError("the outer callback still works")

    with pytest.raises(LookupError, match="the outer callback still works"):
        rendulic.run(tiny_toml, tmp_path / "outer", threads=1, quiet=True, progress=progress)
    assert errors == ["rendulic.run and rendulic.probe cannot be called from a progress "
                      "callback: the call that reports is still running"]
    assert not (tmp_path / "inner").exists()
    assert not (tmp_path / "outer" / "results.h5").exists()


def test_runs_in_two_threads_take_turns_each_with_its_callback(tiny_toml, tmp_path):
    # The observer and the stop flag are the process's: one thread's raising callback stopped
    # the other thread's run ("stopped on request"), and one callback got the other's reports.
    seen = {"a": [], "b": []}
    outcome = {}

    def run(name, raise_at):
        def progress(stage, task, fraction):
            seen[name].append(stage)
            if stage == raise_at:
                raise LookupError(name)
        try:
            rendulic.run(tiny_toml, tmp_path / name, threads=1, quiet=True, progress=progress)
            outcome[name] = "finished"
        except LookupError as e:
            outcome[name] = f"stopped by {e}"

    threads = [threading.Thread(target=run, args=("a", "prepare")),
               threading.Thread(target=run, args=("b", None))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert outcome == {"a": "stopped by a", "b": "finished"}
    assert seen["a"] == ["prepare"]
    assert {"prepare", "states", "probes", "calibration"} <= set(seen["b"])
    assert (tmp_path / "b" / "results.h5").exists()
    assert not (tmp_path / "a" / "results.h5").exists()


def test_damaged_results_files_are_input_errors(cli_run, tmp_path):
    # Each was a bare UnicodeDecodeError, a KeyError, a State of shape (0, 3), or parameters
    # paired by position with the extra ones dropped and a repeated name overwritten.
    import shutil
    h5py = pytest.importorskip("h5py")

    def damaged(name, damage):
        f = tmp_path / f"{name}.h5"
        shutil.copy(cli_run, f)
        with h5py.File(f, "r+") as h:
            damage(h)
        return rendulic.Results(f)

    def foreign_name(h):
        h.move("/states/a", b"/states/\xffa")
    with pytest.raises(rendulic.InputError, match=r"a name or text in the file is not UTF-8: "
                                                  r"b'\\xffa'"):
        damaged("name", foreign_name).states()

    def flat_stress(h):
        del h["/states/a/stress"]
        h.create_dataset("/states/a/stress", shape=(0, 3), dtype="f8")
    with pytest.raises(rendulic.InputError, match=r"/states/a/stress.*is not 3x3"):
        damaged("flat", flat_stress).state("a")

    # Grown over chunks never written: a MemoryError (the reader asked for 24 TiB).
    def grown(h):
        del h["/states/a/positions"]
        h.create_dataset("/states/a/positions", shape=(2**40, 3), maxshape=(None, 3),
                         chunks=(64, 3), dtype="f8")
    with pytest.raises(rendulic.InputError,
                       match=r"/states/a/positions: declares 3298534883328 values but holds "
                             r"the bytes of 0 \(a damaged or unfinished file\)"):
        damaged("grown", grown).state("a")

    def no_fabric(h):
        del h["/states/a/fabric"]
    with pytest.raises(rendulic.InputError, match=r"state 'a' has no fabric"):
        damaged("no_fabric", no_fabric).state("a")

    models = [m for m in h5py.File(cli_run, "r")["/calibration"]
              if "param_names" in h5py.File(cli_run, "r")[f"/calibration/{m}"].attrs]
    assert models
    group = f"/calibration/{models[0]}"

    def repeated(h):
        names = [n.decode() if isinstance(n, bytes) else n for n in h[group].attrs["param_names"]]
        assert len(names) >= 2
        h[group].attrs["param_names"] = [names[0]] * len(names)
    with pytest.raises(rendulic.InputError, match=rf"{group} @param_names: '.*' given twice"):
        damaged("repeated", repeated).calibration()

    def short(h):
        params = h[f"{group}/params"][()]
        del h[f"{group}/params"]
        h[f"{group}/params"] = params[:-1]
    with pytest.raises(rendulic.InputError,
                       match=rf"{group}/params holds \d+ values for \d+ names in @param_names"):
        damaged("short", short).calibration()


def test_closed_standard_streams_keep_the_results_file_whole(tiny_toml, tmp_path):
    # A session whose parent closed its stdout and stderr: the next file opened takes their
    # numbers, and a results file that took one received the messages meant for them.
    import subprocess
    import sys
    out = tmp_path / "out"
    code = ("import rendulic\n"
            f"rendulic.run({str(tiny_toml)!r}, {str(out)!r}, threads=1)\n")

    def close_standard_streams():
        os.close(1)
        os.close(2)
    r = subprocess.run([sys.executable, "-c", code], preexec_fn=close_standard_streams)
    assert r.returncode == 0
    results = rendulic.Results(out / "results.h5")
    assert results.calibration()
