"""One parameter schema for every interface: the Python API's signature and checks, the command line's flags and
docs/cli.md's list all come from native/core/parameters.cpp, with the same defaults (the paper's pipeline, smoothed to a physical reach)."""
import inspect
import pathlib
import re
import subprocess

import numpy as np
import pytest

import meniscus
from meniscus import parameters

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUNNY = "splashsurf/bunny_frame_14_7705_particles.vtk"
DAM_BREAK = "splashsurf/double_dam_break_frame_26_4732_particles.vtk"


def test_schema_is_complete_and_consistent():
    names = [p.name for p in parameters.PARAMETERS]
    assert len(names) == len(set(names))
    for p in parameters.PARAMETERS:
        assert p.type in ("flag", "count", "real", "vector3") and p.group and p.label and p.cli.startswith("-")
        assert len(p.help) > 20 and p.help[0].isupper(), p.name
        if not p.required:
            assert p.problem(p.default) is None, f"{p.name}: its default {p.default} is not allowed"
        if p.type == "vector3":
            assert p.default is None and p.problem((0, 1, 2)) is None and "finite" in p.problem((0, float("nan"), 2))
            continue
        if p.automatic is not None:
            assert p.problem(p.automatic) is None and p.problem(p.suggested) is None, p.name
        for name, _ in p.depends_on_conditions:
            assert parameters.BY_NAME[name].type in ("flag", "count", "real") and name != p.name, p.name


def test_reconstruct_signature_is_the_schema():
    signature = inspect.signature(meniscus.reconstruct).parameters
    for p in parameters.PARAMETERS:
        assert p.name in signature, p.name
        if not p.required:
            assert signature[p.name].default == p.python_default
            assert type(signature[p.name].default) is {"flag": bool, "count": int, "real": float,
                                                       "vector3": type(None)}[p.type]
        assert f"  {p.name}: {p.help}" in meniscus.reconstruct.__doc__


def test_a_dependent_parameter_matters_only_while_its_conditions_hold():
    strength = parameters.BY_NAME["smoothing_strength"]
    assert strength.depends_on_conditions == (("smoothing_iterations", True), ("smoothing_reach", False))
    values = parameters.defaults()
    assert not strength.matters(values.get)  # the reach is the default: the iterations' step does not apply
    values["smoothing_reach"] = 0.0
    assert strength.matters(values.get)
    values["smoothing_iterations"] = 0
    assert not strength.matters(values.get)
    assert parameters.BY_NAME["smoothing_length"].matters(lambda name: False)  # no conditions: always


def test_default_reconstruction_is_the_papers_pipeline_with_the_reach(shared):
    positions = meniscus.read_particles(shared / DAM_BREAK).positions
    mesh = meniscus.reconstruct(positions, 0.025)  # nothing but the radius: what the CLI and the add-on do too
    assert mesh.stats["counts"]["smoothing_reach"] == parameters.BY_NAME["smoothing_reach"].default == 4.28
    for stage in ("decimation", "weights", "smoothing", "normals"):
        assert stage in mesh.stats["seconds"], stage
    assert "decimated_configurations" in mesh.stats["counts"]
    raw = meniscus.reconstruct(positions, 0.025, decimate_barnacles=False, smoothing_iterations=0,
                               normal_smoothing_iterations=0)
    smoothed, rough = meniscus.assess_quality(mesh), meniscus.assess_quality(raw)
    assert smoothed["check"]["ok"] and smoothed["bumpiness"] < 0.5 * rough["bumpiness"]


@pytest.mark.parametrize("name, value, message", [
    ("smoothing_strength", 0.0, "smoothing_strength must be a number greater than 0 and at most 1, got 0"),
    ("smoothing_iterations", 2.5, "smoothing_iterations must be a whole number at least 0, got 2.5"),
    ("decimate_barnacles", 1, "decimate_barnacles must be True or False, got 1"),
    ("cube_size", "fine", "cube_size must be a number greater than 0, got 'fine'"),
    ("weights_normalization", -2.0, "weights_normalization must be a number greater than 0, or 0 for automatic"),
    ("threads", -1, "threads must be a whole number at least 1 and at most 4096, or 0 for automatic (all), got -1"),
])
def test_bad_values_name_the_parameter_and_the_allowed_values(name, value, message):
    with pytest.raises(ValueError) as error:
        meniscus.reconstruct(np.zeros((1, 3), np.float32), 0.025, **{name: value})
    assert message in str(error.value)


def test_unknown_parameter_is_a_type_error_listing_the_parameters():
    with pytest.raises(TypeError, match="unknown parameter.*'smoothing_beta'.*smoothing_strength"):
        meniscus.reconstruct(np.zeros((1, 3), np.float32), 0.025, smoothing_beta=0.5)


def test_numbers_are_formatted_for_people():
    assert parameters.format_value(parameters.BY_NAME["smoothing_strength"], 0.0) == "0"
    assert parameters.format_value(parameters.BY_NAME["cube_size"], np.float32(0.1)) == "0.1"
    assert parameters.format_value(parameters.BY_NAME["memory_budget"], 0.0) == "0 (auto)"
    assert meniscus.parameters.BY_NAME["particle_radius"].problem(0.0) == "must be a number greater than 0, got 0"


def _help_entry(help_text, names):
    """The help of one option: its line and the wrapped lines below it, up to the next option."""
    lines = help_text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.strip().startswith(names + " "))
    end = next((i for i in range(start + 1, len(lines)) if lines[i].strip().startswith("-")), len(lines))
    return " ".join(line.strip() for line in lines[start:end])


def test_command_line_flags_and_defaults_are_the_schema(cli):
    help_text = subprocess.run([cli, "reconstruct", "--help"], capture_output=True, text=True).stdout
    for p in parameters.PARAMETERS:
        entry = _help_entry(help_text, p.cli)
        assert p.help.split(":")[0] in entry, p.name
        if p.type == "vector3":
            assert entry.startswith(f"{p.cli} X Y Z"), (p.name, entry)
        elif p.cli_style == "value" and not p.required:
            default = p.automatic_word if p.automatic == p.default else meniscus._core.format_number(p.default)
            assert entry.startswith(f"{p.cli} ") and re.match(r"\S+ \S+=" + re.escape(default) + r"\b", entry), (p.name, entry)
        elif p.cli_style == "on_off":
            assert f"[default: {'on' if p.default else 'off'}]" in entry, (p.name, entry)


def test_cli_page_lists_every_flag():
    page = (ROOT / "docs" / "cli.md").read_text()
    missing = [p.cli for p in parameters.PARAMETERS if not any(f"`{name}" in page for name in p.cli.split(","))]
    assert not missing, f"docs/cli.md does not mention {missing}"
