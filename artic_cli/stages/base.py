"""What every stage shares: its declaration, its freshness key, and the check that an input is usable.

A stage declares the config sections it reads and the stages whose artefacts it reads.  Its artefact
records a :class:`~artic_cli.io.store.Provenance`: the hash of those sections (and nothing else of the
config), the content hashes of its inputs, the hash of its code (:func:`artic_cli.io.fingerprint.code_hash`)
and its parameters.  A stage whose artefact already records the same recipe is up to date and computes
nothing.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..config import Config, ConfigView
from ..io.fingerprint import code_hash, sections_hash
from ..io.store import Provenance, stored_recipe


@dataclass(frozen=True)
class Stage:
    name: str  # make target and report key, e.g. "epmaps"
    module: str  # the stage module (its code and what it imports make the code hash)
    sections: tuple[str, ...]  # config sections it reads
    reads: tuple[str, ...] = ()  # stages whose artefacts it reads
    kind: str = ""  # the artefact's kind attribute
    hint: str = ""  # how a user makes the artefact

    def view(self, cfg: Config) -> ConfigView:
        return ConfigView(cfg, self.sections)

    def provenance(self, cfg: Config | None, inputs: dict | None = None, params: dict | None = None,
                   code_roots: tuple[str, ...] = (), sections: tuple[str, ...] | None = None) -> Provenance:
        """The recipe of a run; ``sections``: the part of the declared sections this run reads, if less."""
        used = self.sections if sections is None else sections
        return Provenance(stage=self.name, sections_sha256=sections_hash(cfg, used) if cfg else "",
                          inputs=dict(inputs or {}), code_sha256=code_hash(self.module, *code_roots),
                          params=dict(params or {}))


def up_to_date(path: Path | str, prov: Provenance) -> bool:
    """Whether ``path`` already holds what ``prov`` would make (same recipe, this schema, readable)."""
    return stored_recipe(path) == prov.recipe
