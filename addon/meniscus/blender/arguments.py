"""api.reconstruct's arguments from a surface's settings, and the core's words put in the panel's.

Free of Blender's UI: the updater uses it (update.py), and so does the settings module that defines the panel's
properties (properties.py), which in turn calls the updater when a setting changes; keeping these here leaves no
import circle between the two.
"""
import re

from .. import parameters
from . import container

# Pipeline parameters the add-on sets itself: normals follow "Custom Normals", cube_size has a viewport and a
# render value (`cube_size` and `render_cube_size`, the names .blend files already have).
DRIVEN_BY_ADDON = {"normals", "cube_size"}
RENDER_CUBE_SIZE = "render_cube_size"


def pipeline_arguments(settings, for_render, normals=None):
    """api.reconstruct's keyword arguments from a surface's settings: every schema parameter, automatic ones at
    their automatic value when switched so, the render or the viewport cube size, normals when custom normals are on
    (or as given)."""
    arguments = {}
    for parameter in parameters.PARAMETERS:
        if parameter.name in DRIVEN_BY_ADDON:
            continue
        if parameter.type == "vector3":  # boxes: from the container object, below
            continue
        value = getattr(settings, parameter.name)
        if parameter.automatic is not None and getattr(settings, parameter.name + "_auto"):
            value = parameters.convert(parameter, parameter.automatic)
        arguments[parameter.name] = value
    arguments.update(container.box_arguments(settings))
    arguments["cube_size"] = getattr(settings, RENDER_CUBE_SIZE) if for_render else settings.cube_size
    arguments["normals"] = settings.use_custom_normals if normals is None else normals
    return arguments


def label_of(name, for_render=True):
    """The label under which the panel shows a pipeline parameter."""
    if name == "cube_size":
        return "Render Cube Size" if for_render else "Viewport Cube Size"
    if name == "normals":
        return "Custom Normals"
    return parameters.BY_NAME[name].label


def argument_problems(arguments, for_render=True):
    """What is wrong with the arguments, in the panel's words ('Smoothing Strength must be a number greater than 0
    and at most 1, got 0'): the add-on checks before the core is called, so a user never sees an internal name."""
    problems = []
    for name, value in arguments.items():
        problem = parameters.BY_NAME[name].problem(value)
        if problem:
            problems.append(f"{label_of(name, for_render)} {problem}")
    return problems


_LONG_NUMBER = re.compile(r"-?\d{10,}(?:\.\d+)?")
_CLI_FLAG = re.compile(r" \((?:-\w, ?)?--[\w-]+\)")


def in_panel_terms(message, for_render=True):
    """A message of the core in the panel's words: parameter names become their labels ('pass skip_invalid
    (--skip-invalid)' -> "turn on 'Skip Invalid Particles'"), command-line flags go, and numbers printed with dozens
    of digits are shortened (3.4e+38)."""
    message = _CLI_FLAG.sub("", message)
    # Only the identifiers (skip_invalid): single words (threads, normals) are also plain English.
    names = sorted((p.name for p in parameters.PARAMETERS if "_" in p.name), key=len, reverse=True)
    message = re.sub(r"\bpass (" + "|".join(names) + r")\b", r"turn on \1", message)
    message = re.sub(r"\b(" + "|".join(names) + r")\b", lambda m: f"'{label_of(m.group(1), for_render)}'", message)
    return _LONG_NUMBER.sub(lambda m: f"{float(m.group(0)):.3g}", message)
