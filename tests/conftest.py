"""Shared fixtures: the default config, its mesh and model, a mesh file."""

from __future__ import annotations

import importlib
import os
from pathlib import Path

import numpy as np
import pytest
import yaml

from artic_cli.config import load_config
from artic_cli.geometry.mesh import tongue_mesh
from artic_cli.geometry.wall import wall_surface
from artic_cli.mechanics.model import build_model
from artic_cli.stages.mesh import build_mesh

ROOT = Path(__file__).resolve().parent.parent
LONGEST_FIRST = ("test_pipeline.py", "test_solver.py", "test_epmap.py")  # the modules that take longest


IN_CI = bool(os.environ.get("CI"))  # CI installs every test extra and runs every test: a skip there is a failure


def need(module: str):
    """``module`` imported; without it the test is skipped on a developer's machine and fails under CI (the
    ``CI`` environment variable set), where the test extras (``.[test]``) and every dependency are installed."""
    try:
        return importlib.import_module(module)
    except ImportError as err:
        if IN_CI:
            pytest.fail(f"{module} is not installed ({err}); CI installs '.[test]', so a missing module is a "
                        "broken install, not a test to skip", pytrace=False)
        pytest.skip(f"{module} is not installed (pip install -e '.[test]')", allow_module_level=True)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Under CI a skipped test fails, naming the skip's reason: no cross-check can vanish without a word."""
    outcome = yield
    rep = outcome.get_result()
    if IN_CI and rep.skipped and not hasattr(rep, "wasxfail"):
        reason = rep.longrepr[2] if isinstance(rep.longrepr, tuple) else str(rep.longrepr)
        rep.outcome = "failed"
        rep.longrepr = f"skipped under CI, which runs every test: {reason}"


def praat_formants_near(wav, times, expected) -> tuple[list[float], list[float]]:
    """Praat (Burg: 5 formants below 5 kHz, 25-ms windows) on a WAV: each formant's median over ``times``, and
    for each ``expected`` value the one nearest it (Burg may insert spurious peaks, so not by index)."""
    parselmouth = need("parselmouth")
    fm = parselmouth.Sound(str(wav)).to_formant_burg(0.01, 5, 5000, 0.025, 50)
    found = [f for f in (np.nanmedian([fm.get_value_at_time(j, t) for t in times]) for j in range(1, 6))
             if np.isfinite(f)]
    return [min(found, key=lambda f: abs(f - e)) for e in expected], found


def praat_level_db(wav, t0: float, t1: float, above_hz: float | None = None) -> float:
    """Praat's intensity (dB) of a WAV between t0 and t1 s, all of it or (``above_hz``) its band above that
    frequency (a Hann band filter); digital silence reads -300 dB, as Praat's intensity contour has it."""
    parselmouth = need("parselmouth")
    from parselmouth.praat import call

    part = parselmouth.Sound(str(wav)).extract_part(from_time=t0, to_time=t1)
    if above_hz is not None:
        part = call(part, "Filter (pass Hann band)", above_hz, 0, 100)
    level = call(part, "Get intensity (dB)")
    return float(level) if np.isfinite(level) else -300.0


def praat_silences(wav, below_db: float, t0: float = 0.0, t1: float | None = None,
                   min_ms: float = 10.0) -> list[tuple[float, float]]:
    """The stretches (start, end s) where Praat's intensity contour (8-ms windows, 1-ms steps) stays below
    ``below_db``, at least ``min_ms`` long, between t0 and t1."""
    parselmouth = need("parselmouth")
    contour = parselmouth.Sound(str(wav)).to_intensity(minimum_pitch=400.0, time_step=0.001)
    t, db = contour.xs(), contour.values[0]
    inside = (t >= t0) & (t <= (t[-1] if t1 is None else t1))
    quiet = (db < below_db) & inside
    out, start = [], None
    for k, q in enumerate(np.r_[quiet, False]):
        if q and start is None:
            start = k
        elif not q and start is not None:
            if t[k - 1] - t[start] >= min_ms / 1e3:
                out.append((float(t[start]), float(t[k - 1])))
            start = None
    return out


def praat_f0(wav, times) -> np.ndarray:
    """Praat's F0 (Hz; autocorrelation, 75-500 Hz) at ``times`` (NaN where it finds none)."""
    parselmouth = need("parselmouth")
    pitch = parselmouth.Sound(str(wav)).to_pitch(time_step=0.005, pitch_floor=75.0, pitch_ceiling=500.0)
    return np.array([pitch.get_value_at_time(float(t)) for t in times], dtype=float)


CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync")
_CHECKER = """<script>
window.addEventListener("load", function () {
  var out = {images: [], audio: []};
  Array.prototype.forEach.call(document.images, function (im) { out.images.push([im.getAttribute("src"),
                                                                                im.naturalWidth]); });
  var list = document.getElementsByTagName("audio"), left = list.length;
  function done() { var pre = document.createElement("pre"); pre.id = "artic-check";
                    pre.textContent = JSON.stringify(out); document.body.appendChild(pre); }
  if (!left) { done(); return; }
  Array.prototype.forEach.call(list, function (a) {
    function report() { out.audio.push([a.getAttribute("src"), isFinite(a.duration) ? a.duration : -1,
                                        a.error ? a.error.code : 0]); if (--left === 0) { done(); } }
    if (a.readyState >= 1) { report(); } else { a.addEventListener("loadedmetadata", report, {once: true});
                                                a.addEventListener("error", report, {once: true}); a.load(); }
  });
});
</script>"""


def chromium() -> str:
    """Debian's chromium (``.ci/run`` installs it); without it the test skips, and fails under CI."""
    import shutil

    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        if IN_CI:
            pytest.fail("chromium is not installed; .ci/run installs Debian's chromium", pytrace=False)
        pytest.skip("chromium is not installed (apt-get install chromium)")
    return exe


def browser_check(page: Path, tmp: Path, screenshot: Path) -> dict:
    """Open ``page`` in headless Chromium from the file system: a screenshot of its top, and what the browser
    made of it: every image's natural width and every audio element's duration (s) and error code."""
    import json
    import re
    import subprocess

    exe = chromium()
    subprocess.run([exe, *CHROMIUM_FLAGS, f"--user-data-dir={tmp / 'shot'}", "--window-size=1280,1800",
                    f"--screenshot={screenshot}", page.resolve().as_uri()], capture_output=True, timeout=120)
    probe = page.with_name(f".{page.stem}-check.html")
    probe.write_text(page.read_text().replace("</body>", _CHECKER + "</body>"))
    try:
        res = subprocess.run([exe, *CHROMIUM_FLAGS, f"--user-data-dir={tmp / 'dom'}",
                              "--autoplay-policy=no-user-gesture-required", "--virtual-time-budget=30000",
                              "--dump-dom", probe.resolve().as_uri()], capture_output=True, text=True, timeout=120)
    finally:
        probe.unlink()
    found = re.search(r'<pre id="artic-check">(.*?)</pre>', res.stdout, re.S)
    assert found, res.stderr[-2000:]
    return json.loads(found.group(1).replace("&quot;", '"'))


def report_rows(path) -> list[list[str]]:
    """A report's rows (reports/paper.md's tables): item, paper, ours, verdict."""
    rows = []
    for line in Path(path).read_text().splitlines():
        if line.startswith("| ") and not line.startswith("| item"):
            rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


def newly_differing(rows: list[list[str]], accepted: tuple[str, ...]) -> list[str]:
    """The items of rows that differ from the paper and whose item starts with none of ``accepted``."""
    return [r[0] for r in rows if r[3].startswith("differs") and not r[0].startswith(accepted)]


def pytest_collection_modifyitems(items):
    """The longest modules first, so that two workers (``-n 2 --dist loadfile``) finish together."""
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


def run_cli(*args):
    """``artic ARGS`` in-process; anything but a clean exit (a traceback) fails the test."""
    from typer.testing import CliRunner

    from artic_cli.cli.main import app

    res = CliRunner().invoke(app, [str(a) for a in args])
    assert res.exception is None or isinstance(res.exception, SystemExit), repr(res.exception)
    return res


@pytest.fixture(scope="session")
def cfg():
    return load_config(ROOT / "configs" / "default.yaml")


@pytest.fixture(scope="session")
def mesh(cfg):
    return tongue_mesh(cfg.speaker.tongue)


@pytest.fixture(scope="session")
def wall(cfg):
    return wall_surface(cfg.speaker.wall)


@pytest.fixture(scope="session")
def model(cfg, mesh):
    return build_model(mesh, cfg.materials.tongue, cfg.simulation)


@pytest.fixture(scope="session")
def art(cfg, mesh, wall):
    """The whole articulator (tongue, jaw, hyoid, muscles, contact)."""
    from artic_cli.mechanics.model import build_articulator

    return build_articulator(cfg, mesh, wall)


def _articulator(cfg, mesh, wall, mirror: bool):
    from artic_cli.mechanics.model import build_articulator

    sim = cfg.simulation.model_copy(update={"mirror_symmetry": mirror})
    return build_articulator(cfg.model_copy(update={"simulation": sim}), mesh, wall)


@pytest.fixture(scope="session")
def art_whole(cfg, mesh, wall):
    """The articulator solved whole (``simulation.mirror_symmetry`` off)."""
    return _articulator(cfg, mesh, wall, False)


@pytest.fixture(scope="session")
def art_half(cfg, mesh, wall):
    """The articulator solved by halves: its left half moves as the mirror image of its right half."""
    return _articulator(cfg, mesh, wall, True)


@pytest.fixture(scope="session")
def mesh_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("mesh") / "mesh.h5"
    build_mesh(ROOT / "configs" / "default.yaml", out)
    return out


@pytest.fixture(scope="session")
def other_mesh_file(tmp_path_factory):
    """A mesh of another speaker (configs/speaker_small.yaml): different content."""
    out = tmp_path_factory.mktemp("other-mesh") / "mesh.h5"
    build_mesh(ROOT / "configs" / "speaker_small.yaml", out)
    return out


def set_force(model, sets: dict[str, tuple[float, float, float]]) -> np.ndarray:
    """Nodal force array (dyn) from {node set: total force in N}."""
    f = np.zeros((model.n_nodes, 3))
    for name, fn in sets.items():
        idx = model.node_set(name)
        f[idx] += np.asarray(fn) * 1e5 / len(idx)
    return f


@pytest.fixture(scope="session")
def small_maps(tmp_path_factory, mesh_file):
    """Rest-jaw maps: three vectors and one net (the default speaker): (their folder, their config)."""
    from artic_cli.stages.epmap import build_ep_maps

    tmp = tmp_path_factory.mktemp("amaps")
    d = yaml.safe_load((ROOT / "configs" / "default.yaml").read_text())
    d["epmap"] = dict(d.get("epmap", {}), jaw_positions={"rest": {}}, typical_jaw="rest", muscles=["GGp", "HG", "SG"],
                      levels_n=[0.0, 1.0, 2.5, 4.0], pair_levels_n=[1.0, 2.5, 4.0], pairs_tip=[["GGp", "HG"]],
                      pairs_dorsum=[], groups=[], net_jaw_positions=["rest"])
    cfg = tmp / "cfg.yaml"
    cfg.write_text(yaml.safe_dump(d, sort_keys=False))
    build_ep_maps(mesh_file, cfg, tmp / "maps.h5", jobs=2, cache=tmp / "cache")
    return tmp, cfg

