"""Render the Makefile's rules from the stage table (:mod:`artic_cli.stages.table`) and a pipeline
definition (``pipelines/*.yaml``: which schedules, experiments and targets), and split a config into one
file per section.

    python -m artic_cli.pipeline rules pipelines/paper.yaml > data/.pipeline.mk
    python -m artic_cli.pipeline sections configs/default.yaml data/.config

Every data rule depends on exactly what its stage reads: the artefacts before it, the config sections it
declares (``{out}/.config/<section>.json``, rewritten only when that section changes) and the source files
its module imports (plots and the CLI excluded).  A stage whose output comes out the same keeps the old
file's time (see :mod:`artic_cli.io.store`); make's rule for it is a stamp, so nothing downstream reruns.
Figures are rules of their own: a plotting edit redraws pictures and recomputes nothing.
"""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

from .config import SECTIONS, load_config, read_yaml
from .errors import ArticError
from .io.fingerprint import module_closure, module_path
from .validation import Strict, parse

ROOT = Path(__file__).resolve().parent.parent


class Pipeline(Strict):
    pipeline: str
    tissue_schedules: list[str] = []
    tissue_without_constraint: list[str] = []
    articulator_schedules: list[str] = []
    animated: list[str] = []
    tract_schedules: list[str] = []  # articulator schedules whose simulations get a vocal tract and acoustics
    experiments: list[str] = []
    targets: list[str] = []
    vowels: list[str] = []  # configs/targets/vowels/*.yaml
    utterances: list[str] = []  # configs/utterances/*.yaml
    words: list[str] = []  # configs/words/*.yaml (text)


def load_pipeline(path: Path | str) -> Pipeline:
    p = parse(Pipeline, read_yaml(path, "pipeline"), str(path), "pipeline definition", "fix it and rerun make")
    from .experiments.paper import EXPERIMENTS

    for name in p.tissue_schedules + p.tissue_without_constraint + p.articulator_schedules + p.animated:
        if not (ROOT / "configs" / "schedules" / f"{name}.yaml").is_file():
            raise ArticError(f"{path}: schedule '{name}' has no configs/schedules/{name}.yaml")
    for name in p.tract_schedules:
        if name not in p.articulator_schedules:
            raise ArticError(f"{path}: tract_schedules lists '{name}', which articulator_schedules does not simulate; "
                             "add it there")
    for name in p.experiments:
        if name not in EXPERIMENTS:
            raise ArticError(f"{path}: unknown experiment '{name}'; valid: {', '.join(EXPERIMENTS)}")
    for name in p.targets:
        if not (ROOT / "configs" / "targets" / f"{name}.yaml").is_file():
            raise ArticError(f"{path}: target '{name}' has no configs/targets/{name}.yaml")
    for name in p.vowels:
        if not (ROOT / "configs" / "targets" / "vowels" / f"{name}.yaml").is_file():
            raise ArticError(f"{path}: vowel '{name}' has no configs/targets/vowels/{name}.yaml")
    for name in p.utterances:
        if not (ROOT / "configs" / "utterances" / f"{name}.yaml").is_file():
            raise ArticError(f"{path}: utterance '{name}' has no configs/utterances/{name}.yaml")
    for name in p.words:
        if not (ROOT / "configs" / "words" / f"{name}.yaml").is_file():
            raise ArticError(f"{path}: word '{name}' has no configs/words/{name}.yaml")
    return p


def _files(*modules: str, plots: bool = False) -> list[str]:
    """Source files of ``modules`` and what they import; for a plot module, the plotting modules it imports
    (what it draws from is the figure rule's input artefacts, whose own rules follow the physics)."""
    names = module_closure(*modules, within="artic_cli.plots" if plots else None)
    return [str(module_path(m).relative_to(ROOT)) for m in names]


def _fill(text: str, **kw: str) -> str:
    base = {"out": "$(OUT)", "report": "$(REPORT)", "config": "$(CONFIG)", "mesh": "$(OUT)/mesh.h5",
            "maps": "$(OUT)/epmaps.h5", "dynamic": "$(OUT)/dynamic.h5"}
    base.update(kw)
    for _ in range(2):  # one level of nesting ({output} may hold {name})
        text = text.format_map(_Keep(base))
    return text


class _Keep(dict):
    def __missing__(self, key):
        return "{" + key + "}"


def render(p: Pipeline) -> str:
    from .stages.table import REPORT_MODULE, REPORT_OUTPUT, STAGES

    lines = [f"# generated from the stage table and the {p.pipeline} pipeline definition; do not edit", ""]
    artefacts: list[str] = []
    figures: list[str] = []
    targets: dict[str, list[str]] = {}
    stamps: dict[str, str] = {}  # output -> its stamp
    reads: dict[str, list[str]] = {}  # output -> what its stage reads
    alone: dict[str, list[tuple[str, list[str]]]] = {"first": [], "last": []}  # (stamp, its outputs and figures)
    for st in STAGES:
        module = importlib.import_module(st.module)
        sections = [f"$(OUT)/.config/{s}.json" for s in module.STAGE.sections]
        src = " ".join(_files(st.module))
        items = getattr(p, st.items) if st.items else [""]
        outs = []
        for name in items:
            kw = {"name": name, "schedule": f"configs/schedules/{name}.yaml", "target": f"configs/targets/{name}.yaml"}
            output = _fill(st.output, **kw)
            kw["output"] = output
            inputs = " ".join(_fill(i, **kw) for i in st.inputs)
            stamp = f"$(OUT)/.stamps/{st.name}/{name or st.name}"
            ok = " || [ $$? -eq 3 ]" if 3 in st.ok_status else ""
            lines += [f"{stamp}: {inputs} {' '.join(sections)} {src} | setup".replace("  ", " "),
                      f"\t@mkdir -p $(dir {output})",
                      f"\t$(ARTIC) {_fill(st.command, **kw)}{ok}",
                      "\t@mkdir -p $(@D) && touch $@",
                      f"{output}: {stamp} ; @test -f $@ || {{ rm -f $<; $(MAKE) --no-print-directory $< OUT=$(OUT) "
                      "CONFIG=$(CONFIG) REPORT=$(REPORT); }", ""]
            outs.append(output)
            stamps[output], reads[output] = stamp, inputs.split()
            if st.alone:
                alone[st.alone].append((stamp, [output]))
            groups: dict[str, list] = {}  # one rule (grouped targets) per plotting command
            for fig in st.figures:
                if not fig.items or name in getattr(p, fig.items, [fig.items]):
                    groups.setdefault(fig.command, []).append(fig)
            for command, figs in groups.items():
                paths = [_fill(f.path, **kw) for f in figs]
                deps = sorted({_fill(i, **kw) for f in figs for i in f.inputs}
                              | {x for f in figs for x in _files(f.module, plots=True)})
                options = " ".join(_fill(f.option, **kw, figure=path) for f, path in zip(figs, paths))
                lines += [f"{' '.join(paths)} &: {output} {' '.join(deps)} | setup",
                          f"\t$(ARTIC) {_fill(command, **kw)} {options}", ""]
                figures += paths
                if st.alone:
                    alone[st.alone][-1][1].extend(paths)
        artefacts += outs
        targets.setdefault(st.name.split("-")[0], []).extend(outs)
    report = _fill(REPORT_OUTPUT)
    lines += _alone_rules(alone, stamps, reads, artefacts + figures)
    lines += [f"{report}: {' '.join(artefacts)} {' '.join(figures)} {' '.join(_files(REPORT_MODULE))} | setup",
              "\t$(ARTIC) report --data $(OUT) --out $@", ""]
    for name, outs in targets.items():
        lines.append(f"{name}: {' '.join(outs)}")
    lines += [f"figures: {' '.join(figures)}", f"paper: {report}",
              f".PHONY: {' '.join(targets)} figures paper", ""]
    return "\n".join(lines)


def _alone_rules(alone: dict, stamps: dict, reads: dict, made: list[str]) -> list[str]:
    """Order-only prerequisites, under `make -j paper` only, that run a stage alone: a ``first`` one before
    every stage that does not feed it, a ``last`` one after everything that does not need it."""
    if len(alone["first"]) > 1:
        raise ArticError("the stage table marks more than one stage alone='first'; they would wait for each other")
    lines = []
    for stamp, own in alone["first"]:
        upstream, todo = set(), [i for o in own if o in reads for i in reads[o]]
        while todo:
            x = todo.pop()
            if x in reads and x not in upstream:
                upstream.add(x)
                todo += reads[x]
        lines += [f"{s}: | {own[0]}" for o, s in stamps.items() if o not in upstream and o not in own]
    lasts = {x for _, own in alone["last"] for x in own}
    for stamp, _ in alone["last"]:
        lines.append(f"{stamp}: | {' '.join(x for x in made if x not in lasts)}")
    return ["ifneq ($(filter paper,$(MAKECMDGOALS)),)", *lines, "endif", ""] if lines else []


def split_sections(config: Path | str, folder: Path | str) -> list[str]:
    """Write each section of a validated config (defaults filled in) to ``folder/<section>.json``; a file
    whose section did not change is left alone (make sees nothing new).  Returns the sections rewritten."""
    cfg = load_config(config)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    changed = []
    for s in SECTIONS:
        if s == "schema_version":
            continue
        text = json.dumps(getattr(cfg, s).model_dump(mode="json"), sort_keys=True, indent=1) + "\n"
        path = folder / f"{s}.json"
        if not path.is_file() or path.read_text() != text:
            tmp = path.with_suffix(".tmp")
            tmp.write_text(text)
            tmp.replace(path)
            changed.append(s)
    return changed


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    try:
        if len(argv) == 2 and argv[0] == "rules":
            sys.stdout.write(render(load_pipeline(argv[1])))
        elif len(argv) == 3 and argv[0] == "sections":
            split_sections(argv[1], argv[2])
        else:
            print("usage: python -m artic_cli.pipeline rules PIPELINE.yaml | sections CONFIG.yaml FOLDER",
                  file=sys.stderr)
            return 2
    except ArticError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
