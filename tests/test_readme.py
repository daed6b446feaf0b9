"""The README's promises: its Python example runs as written, every command it names exists, it stays short."""

from __future__ import annotations

import re
import subprocess
import sys

from conftest import ROOT

README = (ROOT / "README.md").read_text()


def test_the_python_example_runs_as_written(tmp_path):
    code = re.findall(r"```python\n(.*?)```", README, re.S)[0]
    res = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    x, y = map(float, re.search(r"x = (-?[\d.]+) cm, y = (-?[\d.]+) cm after 100 ms", res.stdout).groups())
    # the example's SG 4 N + JO 3 N for 100 ms move the tip from its rest (settled as the example settles it)
    # back toward the styloid by half a centimetre or more (Fig. 4's SG: the tip runs back fastest of the points)
    from artic_cli.config import load_config
    from artic_cli.geometry.mesh import tongue_mesh
    from artic_cli.geometry.wall import wall_surface
    from artic_cli.mechanics.model import build_articulator
    from artic_cli.mechanics.simulate import settle

    cfg = load_config()
    model = build_articulator(cfg, tongue_mesh(cfg.speaker.tongue), wall_surface(cfg.speaker.wall))
    rx, ry = settle(model).x[model.control_points()["tip"], :2]
    assert x < rx - 0.5, ((x, y), (rx, ry))


def test_every_command_in_the_stage_table_exists():
    from typer.main import get_command

    from artic_cli.cli.main import app

    cli = get_command(app)
    for cmd in re.findall(r"\| `artic ([a-z-]+)", README):
        assert cmd in cli.commands, cmd


def test_the_readme_is_a_newcomers_page():
    assert len(README.encode()) <= 8200
    first = README.split("```bash\n")[1].split("```")[0].splitlines()
    assert first[0].startswith("make setup && make paper") and first[1].startswith("make setup && make test")
    ci = (ROOT / ".ci" / "run").read_text()
    assert "make setup && make test" in ci
