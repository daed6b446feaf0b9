"""Render a pipeline definition (``pipelines/*.yaml``) as make variables the Makefile includes.

    python -m artic_cli.pipeline pipelines/paper.yaml > data/.pipeline.mk

Checks that every schedule, experiment and target it names exists, so a typo stops ``make`` at once
with one line naming it.
"""

from __future__ import annotations

import sys
from pathlib import Path

from pydantic import BaseModel, ConfigDict, ValidationError

from .config import read_yaml
from .errors import ArticError

ROOT = Path(__file__).resolve().parent.parent


class Pipeline(BaseModel):
    model_config = ConfigDict(extra="forbid")
    pipeline: str
    tissue_schedules: list[str] = []
    tissue_without_constraint: list[str] = []
    articulator_schedules: list[str] = []
    animated: list[str] = []
    experiments: list[str] = []
    targets: list[str] = []
    stages: dict[str, dict] = {}


def load_pipeline(path: Path | str) -> Pipeline:
    data = read_yaml(path, "pipeline")
    try:
        p = Pipeline.model_validate(data)
    except ValidationError as err:
        first = err.errors()[0]
        raise ArticError(f"{path}: key '{'.'.join(map(str, first['loc']))}': {first['msg']}") from None
    from .experiments.paper import EXPERIMENTS

    for name in p.tissue_schedules + p.tissue_without_constraint + p.articulator_schedules + p.animated:
        if not (ROOT / "configs" / "schedules" / f"{name}.yaml").is_file():
            raise ArticError(f"{path}: schedule '{name}' has no configs/schedules/{name}.yaml")
    for name in p.experiments:
        if name not in EXPERIMENTS:
            raise ArticError(f"{path}: unknown experiment '{name}'; valid: {', '.join(EXPERIMENTS)}")
    for name in p.targets:
        if not (ROOT / "configs" / "targets" / f"{name}.yaml").is_file():
            raise ArticError(f"{path}: target '{name}' has no configs/targets/{name}.yaml")
    return p


def render(p: Pipeline) -> str:
    lines = [f"# generated from the {p.pipeline} pipeline definition; do not edit"]
    for var, items in (("TISSUE_SIMS", p.tissue_schedules), ("NOVOL_SIMS", p.tissue_without_constraint),
                       ("ART_SIMS", p.articulator_schedules), ("ANIMATED", p.animated),
                       ("EXPS", p.experiments), ("TARGET_NAMES", p.targets)):
        lines.append(f"{var} := {' '.join(items)}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m artic_cli.pipeline PIPELINE.yaml", file=sys.stderr)
        return 2
    try:
        sys.stdout.write(render(load_pipeline(argv[0])))
    except ArticError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
