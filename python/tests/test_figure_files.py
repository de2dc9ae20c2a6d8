"""Figure files follow the rules of every file rendulic writes (docs/usage.md "Results are
atomic"): a replaced figure keeps its permissions (savefig's new file had 644, so a figure of
mode 600 became readable by all), and a figure the user may not write is refused, not replaced.
The figure script (app/plot.py) is loaded from the source tree; its save() writes every format."""
import importlib.util
import os
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from conftest import SOURCE

PLOT = SOURCE / "app" / "plot.py"


def plot_module():
    spec = importlib.util.spec_from_file_location("rendulic_plot_script", PLOT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def save_once(plot, out):
    fig, ax = plot.plt.subplots(figsize=(2, 2))
    ax.plot([0, 1], [0, 1])
    plot.save(fig, str(out), "f", {"written": []})


def test_a_replaced_figure_keeps_its_permissions(tmp_path):
    plot = plot_module()
    save_once(plot, tmp_path)
    for ext in plot.FORMATS:
        os.chmod(tmp_path / f"f.{ext}", 0o600)
    save_once(plot, tmp_path)
    for ext in plot.FORMATS:
        assert stat.S_IMODE(os.stat(tmp_path / f"f.{ext}").st_mode) == 0o600, ext
    assert sorted(os.listdir(tmp_path)) == sorted(f"f.{ext}" for ext in plot.FORMATS)


@pytest.fixture
def shared_folder():
    """A folder anyone may enter and write (pytest's own are root's alone)."""
    folder = tempfile.mkdtemp(prefix="rendulic-figures-")
    os.chmod(folder, 0o777)
    yield Path(folder)
    shutil.rmtree(folder, ignore_errors=True)


def test_a_figure_the_user_may_not_write_is_refused(shared_folder):
    plot = plot_module()
    tmp_path = shared_folder
    save_once(plot, tmp_path)
    png = tmp_path / "f.png"
    kept = png.read_bytes()
    os.chmod(png, 0o444)
    # Root may write any file: the script then runs as nobody (util-linux's setpriv).
    prefix = []
    if os.geteuid() == 0:
        if not shutil.which("setpriv"):
            pytest.skip("root without setpriv: cannot run as another user")
        prefix = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"]
    # The script from a copy that user can read: the source tree may be in root's home.
    script = tmp_path / "plot.py"
    shutil.copy(PLOT, script)
    os.chmod(script, 0o644)
    code = ("import importlib.util, sys\n"
            f"spec = importlib.util.spec_from_file_location('p', {str(script)!r})\n"
            "p = importlib.util.module_from_spec(spec); spec.loader.exec_module(p)\n"
            "fig, ax = p.plt.subplots(figsize=(2, 2))\n"
            "try:\n"
            f"    p.save(fig, {str(tmp_path)!r}, 'f', {{'written': []}})\n"
            "except OSError as e:\n"
            "    print(e); sys.exit(7)\n")
    os.mkdir(tmp_path / ".mpl", 0o777)
    os.chmod(tmp_path / ".mpl", 0o777)
    env = dict(os.environ, MPLCONFIGDIR=str(tmp_path / ".mpl"))
    r = subprocess.run(prefix + [sys.executable, "-c", code], capture_output=True, text=True,
                       env=env, cwd=tmp_path)
    assert r.returncode == 7, r.stdout + r.stderr
    assert r.stdout.strip() == f"{png}: cannot write the figure: Permission denied"
    assert png.read_bytes() == kept
    assert not [n for n in os.listdir(tmp_path) if ".tmp-" in n]
