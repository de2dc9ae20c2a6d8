"""Shared fixtures of the Python module's tests (docs/python.md): the rendulic binary the
module's numbers are compared with, and the tiny run of the C++ system tests, made once by the
CLI and once by the module."""
import os
import re
import subprocess
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("RENDULIC_SOURCE_DIR", Path(__file__).resolve().parents[2]))
EXE = os.environ.get("RENDULIC_EXE", str(SOURCE / "build" / "rendulic"))


def cli(*args, check=True):
    """Runs the rendulic binary; returns the completed process (text)."""
    p = subprocess.run([EXE, *map(str, args)], capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"rendulic {' '.join(map(str, args))}: {p.returncode}\n{p.stderr}")
    return p


def cli_error_line(*args):
    """The one-line message the CLI prints for bad input (exit 2), without "rendulic: "."""
    p = cli(*args, check=False)
    assert p.returncode == 2, p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert line.startswith("rendulic: ")
    return line[len("rendulic: "):]


def tiny_scenario_text():
    """The tiny scenario of the C++ system tests (N = 250, every stage a results file holds,
    a few seconds), read from its one home, tests/app/tiny_run.hpp."""
    text = (SOURCE / "tests" / "app" / "tiny_run.hpp").read_text()
    m = re.search(r'kTinyScenario = R"\((.*?)\)";', text, re.S)
    assert m, "tests/app/tiny_run.hpp no longer holds kTinyScenario"
    return m.group(1)


@pytest.fixture(scope="session")
def tiny_toml(tmp_path_factory):
    p = tmp_path_factory.mktemp("scenario") / "tiny.toml"
    p.write_text(tiny_scenario_text())
    return p


@pytest.fixture(scope="session")
def cli_run(tiny_toml, tmp_path_factory):
    """The tiny run made by `rendulic run` (one thread: bitwise reproducible)."""
    out = tmp_path_factory.mktemp("cli_run")
    cli("run", tiny_toml, "--quiet", "--threads", "1", "--out", out)
    return out / "results.h5"


@pytest.fixture(scope="session")
def module_run(tiny_toml, tmp_path_factory):
    """The same run made by rendulic.run, with the progress reports it received."""
    import rendulic
    out = tmp_path_factory.mktemp("module_run")
    reports = []
    r = rendulic.run(tiny_toml, out, threads=1, quiet=True,
                     progress=lambda stage, task, f: reports.append((stage, task, f)))
    return r, reports
