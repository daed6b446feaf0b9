"""Configuration: YAML validated on load, with errors that name the key.

Keys carry their unit in their name (``_cm``, ``_kpa``, ``_ms``, ``_n``) so a
reader of a config never has to guess.  ``load_config`` reads and validates a
file into a frozen :class:`Config`; :class:`ConfigView` restricts one to the
top-level sections a stage declares, so a stage cannot depend on a section
its freshness key leaves out.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import yaml
from pydantic import ValidationError

from ..errors import ArticError
from ..validation import Strict, describe, load_yaml, parse
from .body import *  # noqa: F401,F403  (every section's schema, importable from artic_cli.config)
from .body import (Contact, Cuboid, EPMapSpec, Jaw, Materials, MuscleFunctionSpec, Muscles, Simulation, SolverSpec,
                   Speaker)
from .sound import *  # noqa: F401,F403
from .sound import Acoustics, Speech, VocalTract

DEFAULT_CONFIG = Path(__file__).resolve().parents[2] / "configs" / "default.yaml"


class Config(Strict):
    schema_version: Literal[1]
    speaker: Speaker
    materials: Materials
    simulation: Simulation = Simulation()
    muscles: Muscles = Muscles()
    jaw: Jaw = Jaw()
    contact: Contact = Contact()
    cuboid: Cuboid = Cuboid()
    epmap: EPMapSpec = EPMapSpec()
    solver: SolverSpec = SolverSpec()  # how an answer is verified and refined
    muscle_function: MuscleFunctionSpec = MuscleFunctionSpec()
    acoustics: Acoustics = Acoustics()
    vocal_tract: VocalTract | None = None  # the speaker's tract (required by 'artic vocal-tract')
    speech: Speech = Speech()



def parse_config(data: object, source: Path | str = "<config>") -> Config:
    if not isinstance(data, dict):
        raise ArticError(f"{source}: config must be a YAML mapping; see configs/default.yaml")
    try:
        return Config.model_validate(data)
    except ValidationError as err:
        raise ArticError("config error: " + describe(err, Config, str(source)) + "; fix the key and rerun") from None


def read_yaml(path: Path | str, what: str = "file") -> object:
    path = Path(path)
    if not path.is_file():
        raise ArticError(f"{what} not found: {path}; give an existing path")
    try:
        return load_yaml(path.read_text())
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise ArticError(f"{path}: malformed YAML{where}; fix the syntax and rerun") from None


def load_config(path: Path | str | None = None) -> Config:
    path = Path(path) if path is not None else DEFAULT_CONFIG
    return parse_config(read_yaml(path, "config"), path)


def parse_speaker(data: object, source: str = "<speaker>") -> Speaker:
    return parse(Speaker, data, source, "speaker section", "rebuild the mesh with 'artic build-mesh'")


SECTIONS = tuple(Config.model_fields)


class ConfigView:
    """A config restricted to ``sections``: reading any other top-level section raises (a stage that did
    that would go stale without noticing)."""

    def __init__(self, cfg: Config, sections):
        unknown = set(sections) - set(SECTIONS)
        if unknown:
            raise ValueError(f"unknown config sections {sorted(unknown)}")
        if isinstance(cfg, ConfigView):
            cfg = cfg.full
        self.full, self.sections = cfg, frozenset(sections)

    def __getattr__(self, name: str):
        if name in SECTIONS and name not in self.sections:
            raise AttributeError(f"config section '{name}' was not declared by this stage "
                                 f"(declared: {', '.join(sorted(self.sections))})")
        return getattr(self.full, name)
