"""docs/parameters.md is what scripts/parameter_reference.py makes from the schema: the reference cannot drift."""
import importlib.util
import pathlib

from meniscus import parameters

ROOT = pathlib.Path(__file__).resolve().parents[2]


def load_generator():
    spec = importlib.util.spec_from_file_location("parameter_reference", ROOT / "scripts" / "parameter_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_committed_reference_is_what_the_schema_gives():
    committed = (ROOT / "docs" / "parameters.md").read_text(encoding="utf-8")
    assert committed == load_generator().render(), (
        "docs/parameters.md differs from the schema: run python3 scripts/parameter_reference.py")


def test_every_parameter_has_its_three_spellings_and_default():
    generator = load_generator()
    text = generator.render()
    rows = {line.split(" | ")[0].strip("| `"): line for line in text.splitlines() if line.startswith("| `")}
    assert set(rows) == {p.name for p in parameters.PARAMETERS}
    for p in parameters.PARAMETERS:
        row = rows[p.name]
        assert f"`{p.cli.split(',')[-1]}`" in row and f"| {generator._addon_label(p)} |" in row, row
        if not p.required and p.type not in ("flag", "vector3"):
            assert f" {parameters.format_value(p, p.default)} |" in row, row
