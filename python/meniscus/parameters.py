"""The pipeline's parameters, as the core's schema defines them (native/core/parameters.cpp): name, type, default,
range, unit, help text and their spelling on the command line and in Blender. The Python API builds
reconstruct()'s signature and docstring from it and the Blender add-on its properties, so that every interface has
the same parameters with the same defaults.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Dict, Optional, Tuple

from . import _core


@dataclass(frozen=True)
class Parameter:
    name: str                 # keyword of reconstruct() and the Blender property
    group: str                # surface, mesh, smoothing, normals, output, execution
    type: str                 # "flag", "count", "real" or "vector3" (three numbers or None: unset)
    label: str                # as Blender shows it
    cli: str                  # command-line flag(s)
    cli_style: str            # "value" or "on_off" (a bare switch means on)
    unit: str
    help: str
    default: Optional[float]  # None for vector3 (unset)
    minimum: float
    maximum: float
    minimum_open: bool
    maximum_open: bool
    automatic: Optional[float]  # the value meaning "choose automatically", outside the range
    automatic_word: str
    suggested: float          # a value to offer where the default is automatic or required
    soft_minimum: float
    soft_maximum: float
    required: bool
    depends_on: str           # when it matters: "a,!b" = a on (non-zero) and b off (zero); see depends_on_conditions
    allowed: str              # the allowed values in words

    @property
    def python_default(self):
        """The default as the Python type of the parameter (bool, int or float)."""
        return convert(self, self.default)

    def problem(self, value) -> Optional[str]:
        """What is wrong with a value ('must be greater than 0 and at most 1, got 0'), or None."""
        if self.type == "vector3":
            return _core.parameter_problem(self.name, None if value is None else [float(x) for x in value])
        if self.type == "flag":
            return _core.parameter_problem(self.name, bool(value))
        return _core.parameter_problem(self.name, float(value))

    @property
    def depends_on_conditions(self) -> Tuple[Tuple[str, bool], ...]:
        """(name, must be on) for each condition of depends_on: ("smoothing_iterations", True), ("smoothing_reach", False)."""
        return tuple((c.lstrip("!"), not c.startswith("!")) for c in self.depends_on.split(",") if c)

    def matters(self, is_on) -> bool:
        """Whether this parameter has an effect, given is_on(name): whether that parameter is on (non-zero)."""
        return all(bool(is_on(name)) == on for name, on in self.depends_on_conditions)

    def describe(self) -> str:
        """One line of documentation: meaning, unit, allowed values and default."""
        unit = f" [{self.unit}]" if self.unit else ""
        default = "required" if self.required else f"default {format_value(self, self.default)}"
        allowed = "" if self.type == "flag" else f"; {self.allowed}"
        return f"{self.help}{unit}{allowed}; {default}."


def convert(parameter: Parameter, value):
    if parameter.type == "vector3":
        return None if value is None else tuple(float(x) for x in value)
    if parameter.type == "flag":
        return bool(value)
    if parameter.type == "count":
        return int(value)
    return float(value)


def format_value(parameter: Parameter, value: float) -> str:
    """A value as people read it: True/False, whole numbers without a point, 'auto' where it means automatic."""
    if parameter.type == "vector3":
        return "unset" if value is None else "(" + ", ".join(_core.format_number(float(x)) for x in value) + ")"
    if parameter.automatic is not None and value == parameter.automatic:
        return f"{_core.format_number(value)} ({parameter.automatic_word})"
    if parameter.type == "flag":
        return str(bool(value))
    return _core.format_number(float(value))


PARAMETERS: Tuple[Parameter, ...] = tuple(Parameter(**entry) for entry in _core.parameter_schema())
BY_NAME: Dict[str, Parameter] = {p.name: p for p in PARAMETERS}
GROUPS: Tuple[str, ...] = tuple(dict.fromkeys(p.group for p in PARAMETERS))


def defaults() -> Dict[str, object]:
    """Every parameter that has a default, at its default (the paper's pipeline, smoothed to a physical reach)."""
    return {p.name: p.python_default for p in PARAMETERS if not p.required}


def is_finite_number(value) -> bool:
    try:
        return math.isfinite(float(value))
    except (TypeError, ValueError):
        return False
