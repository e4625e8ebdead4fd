"""The one result schema (docs/schema/result.schema.json): every --json output validates
against it — those the command-line tests kept (SVI_JSON_OUTPUTS, set by .ci/run), and one of
every kind made here — and the guide documents every field it names."""

import glob
import json
import os
import re
import subprocess
import tempfile
from pathlib import Path

import pytest

import svi

jsonschema = pytest.importorskip("jsonschema")

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "schema" / "result.schema.json").read_text(encoding="utf-8"))
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)
KINDS = set(SCHEMA["properties"]["kind"]["enum"])

from test_svi import svi_binary  # noqa: E402


def validate(text, where):
    """Every line of `text` is one JSON object in the schema; their kinds."""
    kinds = []
    for line in text.splitlines():
        if not line.strip():
            continue
        value = json.loads(line)
        errors = sorted(VALIDATOR.iter_errors(value), key=lambda e: list(e.path))
        assert not errors, f"{where}: " + "; ".join(f"{list(e.path)}: {e.message}" for e in errors[:5])
        kinds.append(value["kind"])
    return kinds


def test_the_schema_is_a_valid_json_schema():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


def test_a_renamed_or_mistyped_field_fails_validation():
    """The schema is strict: an unknown name, a missing field or a wrong type is an error."""
    status, stdout, _ = run("run", "kepler", "--t-end", "1", "--json")
    value = json.loads(stdout)
    assert VALIDATOR.is_valid(value)
    for broken in (
        {**value, "solution_err_max": 1.0},
        {k: v for k, v in value.items() if k != "steps"},
        {**value, "steps": "ten"},
        {**value, "schema_version": 2},
    ):
        assert not VALIDATOR.is_valid(broken)


def run(*args):
    """`svi ARGS` (in the system's temporary directory, where a run could write) as (exit
    status, stdout, stderr)."""
    binary = os.path.abspath(svi_binary())
    done = subprocess.run([binary, *args], capture_output=True, text=True, timeout=600, cwd=tempfile.gettempdir())
    return done.returncode, done.stdout, done.stderr


# One output of every kind: success and failure.
COMMANDS = [
    ("run", "kepler", "--t-end", "5", "--json"),
    ("run", "kepler", "--t-end", "5", "--adapt", "step", "--tol", "1e-8", "--output-times", "1,2", "--diagnostics", "energy,momentum,solution", "--json"),
    ("run", "kepler-text", "--t-end", "5", "--json"),
    ("run", "spherical-pendulum", "--t-end", "1", "--json"),
    ("run", "spherical-pendulum", "--h", "100", "--t-end", "1000", "--json"),
    ("run", "fput", "--t-end", "5", "--json"),
    ("run", "heavy-top", "--t-end", "1", "--json"),
    ("run", "falling-body", "--t-end", "1", "--json"),
    ("run", "wave", "--t-end", "0.5", "--json"),
    ("run", "nls-soliton", "--t-end", "0.1", "--json"),
    ("run", "kepler", "--h", "2", "--method", "svi:3", "--divergence-limit", "2", "--json"),
    ("run", "no-such-scene", "--json"),
    ("run", "kepler", "--h", "-1", "--json"),
    ("run", "wave", "--h", "0", "--json"),
    ("ensemble", "kepler", "--param", "e=0.1,0.5", "--t-end", "1", "--json"),
    ("compare", "kepler", "--methods", "svi,verlet", "--t-end", "1", "--json"),
]


def test_every_kind_validates_on_success_and_failure():
    kinds = set()
    for command in COMMANDS:
        _, stdout, stderr = run(*command)
        assert stdout.strip(), (command, stderr)
        kinds.update(validate(stdout, " ".join(command)))
    assert kinds == KINDS


def test_every_json_output_of_the_command_line_tests_validates():
    directory = os.environ.get("SVI_JSON_OUTPUTS")
    if not directory:
        pytest.skip("SVI_JSON_OUTPUTS is not set (.ci/run sets it for the cargo tests)")
    files = sorted(glob.glob(os.path.join(directory, "*.json")))
    assert len(files) > 100, f"only {len(files)} outputs kept in {directory}"
    kinds = set()
    for path in files:
        with open(path, encoding="utf-8") as f:
            record = json.load(f)
        if not record["stdout"].strip():
            continue  # a command killed, or one whose output the test forbids
        try:
            kinds.update(validate(record["stdout"], " ".join(record["args"])))
        except json.JSONDecodeError:
            # A test of a broken pipe or a full device: the output was cut off on purpose.
            assert record["status"] != 0, record["args"]
    assert {"ode", "lie_group", "field", "pseudospectral", "failure"} <= kinds, kinds


def test_the_python_package_reads_the_same_schema():
    result = svi.run("kepler", t_end=5.0)
    assert VALIDATOR.is_valid(result.summary), list(VALIDATOR.iter_errors(result.summary))[:3]
    with pytest.raises(svi.SviError) as failed:
        svi.run("kepler", h=2.0, method="svi:3", divergence_limit=2.0)
    assert VALIDATOR.is_valid(failed.value.summary)


def schema_fields(node=SCHEMA):
    """Every property name the schema defines, at any depth."""
    names = set()
    if isinstance(node, dict):
        names.update(node.get("properties", {}))
        for value in node.values():
            names |= schema_fields(value)
    elif isinstance(node, list):
        for value in node:
            names |= schema_fields(value)
    return names


def test_the_guide_documents_every_field_of_the_schema_and_no_other():
    text = (ROOT / "docs" / "guide" / "src" / "json.md").read_text(encoding="utf-8")
    documented = set(re.findall(r"^\| `([a-z0-9_]+)` \|", text, flags=re.M))
    assert documented == schema_fields(), (
        f"in the schema, not the guide: {sorted(schema_fields() - documented)}; "
        f"in the guide, not the schema: {sorted(documented - schema_fields())}"
    )
