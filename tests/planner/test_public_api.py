"""`planner.__all__` is the public surface, and the README's example runs on it."""

from __future__ import annotations

import re
import types
from pathlib import Path

import planner

README = Path(__file__).resolve().parents[2] / "README.md"


def test_all_names_exactly_the_public_members():
    # both ways: nothing exported that is not bound, nothing bound that is not exported
    public = {
        name
        for name, value in vars(planner).items()
        if not name.startswith("_") and not isinstance(value, types.ModuleType)
    }
    assert set(planner.__all__) == public
    assert planner.__all__ == sorted(set(planner.__all__))


def test_every_export_is_defined_in_a_stage_of_the_planner():
    for name in planner.__all__:
        value = getattr(planner, name)
        module = getattr(value, "__module__", "")
        assert module.startswith("planner."), (name, module)
        # the package hands on the defining module's object, not a copy
        assert getattr(__import__(module, fromlist=[name]), name) is value


def test_the_readme_library_example_runs_on_the_public_api(capsys):
    text = README.read_text(encoding="utf-8")
    section = text.split("## The library in brief", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, flags=re.S).group(1)
    assert "from planner import" in code
    exec(compile(code, str(README), "exec"), {})
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].split()[0] in ("ambiguous", "localized")
