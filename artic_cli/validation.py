"""The one way what a user gives is checked: typed fields for every input format, one parser that turns a
failure into one line naming the file, the key and the fix, and checks for the command line's numbers.

Every YAML or CSV format (config, schedule, target, pipeline, batch rows, and the acoustic formats: tubes,
F0 contours, utterances) is a :class:`Strict` record built from the field types below and read with
:func:`parse`; every numeric command-line option goes through :func:`check_number`.  Numbers are finite
unless a field says otherwise; names that become file names are :data:`SafeName`.
"""

from __future__ import annotations

import difflib
import math
import re
from typing import Annotated, Any

import yaml
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, ValidationInfo

from .errors import ArticError

YAML_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's, where PyYAML was built with it: 5x faster


def load_yaml(text: str) -> Any:
    """YAML text as Python objects (the safe loader: no tags that build objects)."""
    return yaml.load(text, Loader=YAML_LOADER)

DEFAULT_MAX_FORCE_N = 50.0  # the largest muscle or load force accepted unless the config's muscles.max_force_n raises it


class Strict(BaseModel):
    """A user-facing YAML record: unknown keys are errors, values frozen once validated."""

    model_config = ConfigDict(extra="forbid", frozen=True)


def _force_cap(value: float, info: ValidationInfo) -> float:
    cap = (info.context or {}).get("max_force_n", DEFAULT_MAX_FORCE_N)
    if value > cap:
        raise ValueError(f"{value:g} N is above the {cap:g}-N cap (raise muscles.max_force_n in the config if you "
                         "mean it)")
    return value


def _safe_name(value: str) -> str:
    if not SAFE_NAME.fullmatch(value) or value.startswith("."):
        raise ValueError(f"{value!r} is not a safe file name: use letters, digits, '_', '-' and '.', no separators, "
                         "not starting with a dot")
    return value


def increasing(values: list, message: str) -> list:
    """``values`` if each is larger than the one before, else a ValueError with ``message`` (a validator's)."""
    if any(b <= a for a, b in zip(values, values[1:])):
        raise ValueError(message)
    return values


SAFE_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]{0,99}")

Finite = Annotated[float, Field(allow_inf_nan=False)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
ForceN = Annotated[float, Field(ge=0, allow_inf_nan=False), AfterValidator(_force_cap)]  # a muscle's force, N
LoadN = Annotated[float, Field(allow_inf_nan=False)]  # a load component, N (its size is capped per load)
DurationMs = Positive
OnsetMs = NonNegative
PositionCm = Finite
LengthCm = Positive  # a tube's or a segment's length
AreaCm2 = NonNegative  # a cross-sectional area: 0 is a closure
F0Hz = Annotated[float, Field(ge=50, le=500, allow_inf_nan=False)]  # a voice's fundamental frequency
FormantHz = Annotated[float, Field(ge=100, le=5000, allow_inf_nan=False)]  # a formant target
SafeName = Annotated[str, AfterValidator(_safe_name)]  # a name that becomes a file name
Point2 = Annotated[list[Finite], Field(min_length=2, max_length=2)]
Point3 = Annotated[list[Finite], Field(min_length=3, max_length=3)]


def _model_at(model: type[BaseModel], loc: tuple) -> type[BaseModel]:
    """The record type at ``loc`` inside ``model`` (for suggesting keys)."""
    for part in loc:
        if not isinstance(part, str):
            continue
        field = model.model_fields.get(part)
        ann = getattr(field, "annotation", None) if field else None
        candidates = [ann, *getattr(ann, "__args__", ())]
        for a in list(candidates):
            candidates += list(getattr(a, "__args__", ()))
        sub = [a for a in candidates if isinstance(a, type) and issubclass(a, BaseModel)]
        if not sub:
            break
        model = sub[0]
    return model


def describe(err: ValidationError, model: type[BaseModel], source: str) -> str:
    """One line for the first problem of a failed validation: the file, the key, what is wrong."""
    first = err.errors()[0]
    loc = ".".join(str(p) for p in first["loc"])
    kind = first["type"]
    if kind == "extra_forbidden":
        known = _model_at(model, tuple(first["loc"][:-1])).model_fields
        close = difflib.get_close_matches(str(first["loc"][-1]), list(known), n=1)
        hint = f" (did you mean '{close[0]}'?)" if close else f" (valid: {', '.join(known)})"
        return f"{source}: unknown key '{loc}'{hint}"
    if kind == "missing":
        return f"{source}: missing key '{loc}'"
    if kind == "literal_error":
        return f"{source}: key '{loc}': {first['input']!r} is not one of the valid values ({first['msg'].split('Input should be ')[-1]})"
    if kind in ("finite_number",):
        return f"{source}: key '{loc}': {first['input']!r} is not a finite number"
    msg = first["msg"].removeprefix("Value error, ")
    return f"{source}: key '{loc}': {msg}"


def parse(model: type[BaseModel], data: Any, source: str, what: str, fix: str = "fix it and rerun",
          context: dict | None = None):
    """``data`` (from YAML, JSON or CSV) as a ``model`` record; anything wrong is one ArticError naming
    ``source``, the key and ``fix``."""
    if not isinstance(data, dict):
        raise ArticError(f"{source}: a {what} must be a YAML mapping; {fix}")
    try:
        return model.model_validate(data, context=context)
    except ValidationError as err:
        raise ArticError(f"{describe(err, model, source)}; {fix}") from None


def check_number(option: str, value: float | int | None, *, gt: float | None = None, ge: float | None = None,
                 le: float | None = None, unit: str = "") -> None:
    """A numeric command-line option: finite and within its range, else one ArticError naming it."""
    if value is None:
        return
    u = f" {unit}" if unit else ""
    if not math.isfinite(value):
        raise ArticError(f"{option} must be a finite number{u}, got {value}")
    if gt is not None and not value > gt:
        raise ArticError(f"{option} must be greater than {gt:g}{u}, got {value:g}")
    if ge is not None and not value >= ge:
        raise ArticError(f"{option} must be at least {ge:g}{u}, got {value:g}")
    if le is not None and not value <= le:
        raise ArticError(f"{option} must be at most {le:g}{u}, got {value:g}")


def check_name(name: str, source: str, key: str = "name") -> str:
    """A name from a user's file that becomes a file name."""
    try:
        return _safe_name(name)
    except ValueError as err:
        raise ArticError(f"{source}: key '{key}': {err}; rename it") from None


def read_csv(path, columns: list[str], record: type[BaseModel], what: str, hint: str) -> list:
    """A CSV file of numbers with exactly ``columns`` as its header, each row checked as a ``record``; any
    problem is one ArticError naming the file, the line, the key and ``hint``."""
    import csv
    import io
    from pathlib import Path

    path = Path(path)
    if not path.is_file():
        raise ArticError(f"{what} not found: {path}; {hint}")
    try:
        reader = csv.DictReader(io.StringIO(path.read_text()))
        header = [h.strip() for h in (reader.fieldnames or [])]
        records = list(reader)
    except (UnicodeDecodeError, csv.Error):
        raise ArticError(f"{path} is not a readable CSV file; {hint}") from None
    if header != columns:
        raise ArticError(f"{path}: the header must be '{','.join(columns)}', got {','.join(header) or 'nothing'}; "
                         f"{hint}")
    rows = []
    for k, r in enumerate(records, start=2):
        try:
            values = {key.strip(): float(v) for key, v in r.items()}
        except (TypeError, ValueError, AttributeError):
            raise ArticError(f"{path}, line {k}: every value must be a number, got {dict(r)}; {hint}") from None
        rows.append(parse(record, values, f"{path}, line {k}", f"{what} row", hint))
    return rows
