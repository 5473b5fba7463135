"""engine/solver/settings.py: every optimizer setting describes itself once, and the checks,
the choice lists and the documentation are generated from that description."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from engine.errors import UserError
from engine.solver import settings as schema
from engine.solver.setting_schema import META, Setting, setting
from engine.solver.settings import SETTINGS, OptimizerSettings
from engine.solver.settings_edit import SettingsEdit, check_values
from engine.validation import Choice, Flag, Num, ValidationError

DOC = Path(__file__).resolve().parents[2] / "docs" / "optimizer.md"


def test_every_field_has_its_metadata():
    for f in dataclasses.fields(OptimizerSettings):
        info = f.metadata.get(META)
        assert isinstance(info, Setting), f"{f.name}: declare it with setting(...)"
        assert info.label.strip() and info.help.strip(), f.name
        assert isinstance(info.spec, (Num, Choice, Flag)), f.name
        if info.panel and isinstance(info.spec, Num):
            assert info.step > 0, f"{f.name}: a panel number needs a step"
        assert set(info.offered) <= set(getattr(info.spec, "options", ())), f.name
    assert list(SETTINGS) == [f.name for f in dataclasses.fields(OptimizerSettings)]


def test_a_field_declared_without_its_metadata_is_refused():
    @dataclasses.dataclass
    class Partly:
        fine: int = setting(1, "Fine", "Declared.", Num(0, 2, integer=True))
        bare: float = 0.5

    with pytest.raises(TypeError, match=r"Partly.bare: declare it with setting"):
        list(schema.fields(Partly))


def test_defaults_lie_inside_their_own_ranges():
    defaults = OptimizerSettings()  # validates
    for name, spec in SETTINGS.items():
        assert spec.check(getattr(defaults, name)) == getattr(defaults, name), name


def _outside(spec: Num) -> float:
    return spec.hi * 2 + 1 if math.isfinite(spec.hi) else spec.lo - 1


@pytest.mark.parametrize("name", [n for n, s in SETTINGS.items() if isinstance(s, Num)])
def test_a_number_outside_its_range_is_one_line_naming_field_and_range(name):
    spec = SETTINGS[name]
    with pytest.raises(ValidationError) as err:
        OptimizerSettings(**{name: _outside(spec)})
    text = str(err.value)
    assert "\n" not in text and text.startswith(f"optimizer settings: {name} = ")
    assert spec.describe() in text
    with pytest.raises(ValidationError, match=f"{name} = "):
        OptimizerSettings(**{name: "0.1"})  # a string is not a number


@pytest.mark.parametrize("name", [n for n, s in SETTINGS.items() if not isinstance(s, Num)])
def test_choices_and_flags_refuse_other_values(name):
    with pytest.raises(ValidationError, match=f"optimizer settings: {name} = 'nonsense'"):
        OptimizerSettings(**{name: "nonsense"})


def test_open_bounds_and_whole_numbers_are_kept():
    for bad in ({"lr": 0.0}, {"step_size": 0.0}, {"momentum": 1.0}, {"iterations": 2.5}, {"iterations": 0}):
        with pytest.raises(ValidationError):
            OptimizerSettings(**bad)
    s = OptimizerSettings(iterations=6.0, lr=1, root_anchor="none", reach=False)
    assert type(s.iterations) is int and type(s.lr) is float and s.root_anchor == "none"
    with pytest.raises(ValidationError, match="a joint name or 'none'"):
        OptimizerSettings(root_anchor="tail")


def test_choice_lists_come_from_the_schema():
    lists = schema.choices()
    assert lists["mode"] == schema.MODES and lists["optimizer"] == schema.OPTIMIZERS
    assert lists["prior"] == schema.PRIORS and lists["heading"] == schema.HEADINGS
    assert lists["tuning"] == schema.TUNINGS and "lwrist" in lists["root_anchor"]


def test_a_partial_edit_is_checked_by_name():
    assert check_values({"iterations": 3.0, "lr": 1}) == {"iterations": 3, "lr": 1.0}
    with pytest.raises(UserError, match="unknown setting.*'itterations'; known: mode, iterations"):
        check_values({"itterations": 3})
    with pytest.raises(UserError, match=r"optimizer settings: lr = 11 is out of range; allowed: a number in \(0, 10\]"):
        check_values({"lr": 11})


def test_the_class_documents_every_field():
    doc = OptimizerSettings.__doc__ or ""
    for name in SETTINGS:
        assert f"    {name} : " in doc, name


def test_the_settings_table_of_the_optimizer_guide_is_the_generated_one():
    text = DOC.read_text(encoding="utf-8")
    begin, end = "<!-- settings table: generated -->\n", "<!-- end of settings table -->"
    assert begin in text and end in text, "docs/optimizer.md lost its settings-table markers"
    table = text.split(begin, 1)[1].split(end, 1)[0]
    assert table == schema.markdown_table(), "run: PYTHONPATH=. python scripts/settings_table.py"


def test_a_settings_edit_is_checked_immutable_and_merges():
    import pickle

    edit = SettingsEdit({"iterations": 4.0, "mode": "offline"})
    assert dict(edit) == {"iterations": 4, "mode": "offline"} and edit == {"iterations": 4, "mode": "offline"}
    merged = edit | {"iterations": 7, "lr": 0.1}
    assert dict(merged) == {"iterations": 7, "mode": "offline", "lr": 0.1} and edit["iterations"] == 4
    assert pickle.loads(pickle.dumps(merged)) == merged  # crosses to the engine process
    with pytest.raises(TypeError):
        edit["lr"] = 0.2  # type: ignore[index]
    with pytest.raises(UserError, match="scene.json: iterations = 0 is out of range"):
        SettingsEdit({"iterations": 0}, "scene.json")
    with pytest.raises(UserError, match="unknown setting"):
        edit | {"itterations": 1}


def test_the_session_refuses_a_bad_setting_before_it_reaches_the_engine(synthetic_motion):
    from engine.studio.session import Session

    session = Session()
    session.set_motion(synthetic_motion)
    commands = []
    session.attach(commands.append)
    commands.clear()
    for name, value, message in (
        ("lr", 11.0, r"lr = 11.0 is out of range; allowed: a number in \(0, 10\]"),
        ("mode", "fast", "mode = 'fast' is not allowed"),
        ("itterations", 3, "unknown setting"),
    ):
        with pytest.raises(UserError, match=message):
            session.set_setting(name, value)
    assert commands == [] and session.settings["lr"] == OptimizerSettings().lr
    session.set_setting("iterations", 5.0)
    assert commands[-1].values == {"iterations": 5} and isinstance(commands[-1].values, SettingsEdit)
