"""A method is one module of engine/methods: found by the registry, and holding the contract."""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

import pytest

import engine.methods as M
from engine.methods.base import Configurable, Constrainable, DecodesLatents, Method, SensorWeighted, SolvesClips

FOLDER = Path(M.__file__).parent
MODULES = M.method_modules(FOLDER)

#: Each capability's members: a method offers all of them or none (the driver sees whole capabilities).
CAPABILITIES = {
    Configurable: ("configure",),
    Constrainable: ("set_constraints", "add_constraint"),
    SensorWeighted: ("set_sensor_weight",),
    DecodesLatents: ("decode_latent",),
    SolvesClips: ("solve_clip",),
}


def _method_classes(module: str) -> list[type[Method]]:
    mod = importlib.import_module(f"engine.methods.{module}")
    return [
        c
        for c in vars(mod).values()
        if isinstance(c, type) and issubclass(c, Method) and c.__module__ == mod.__name__ and not inspect.isabstract(c)
    ]


def test_the_shipped_methods_are_found():
    assert {"autoencoder", "dragposer", "ik", "rpm", "sparseposer"} <= set(MODULES)
    assert not {"base", "driver", "records", "dragposer_edits"} & set(MODULES)


def test_a_module_with_create_is_a_method_and_a_helper_is_not(tmp_path):
    (tmp_path / "mine.py").write_text("def create(**kwargs):\n    ...\n")
    (tmp_path / "helper.py").write_text("def created_by(x):\n    ...\n")
    assert M.method_modules(tmp_path) == ["mine"]


@pytest.mark.parametrize("module", MODULES)
def test_every_method_module_is_registered_and_keeps_the_contract(module):
    assert module in M.available_methods()
    classes = _method_classes(module)
    assert [c.name for c in classes] == [module], "one Method subclass per module, named after it"
    cls = classes[0]
    assert "deadline" in inspect.signature(cls.step).parameters
    assert "reference" in inspect.signature(cls.reset).parameters
    assert isinstance(cls.needs_ground_truth, bool) and isinstance(cls.takes_deadline, bool)
    for proto, members in CAPABILITIES.items():
        offered = [hasattr(cls, m) for m in members]
        assert all(offered) or not any(offered), f"{module}: part of {proto.__name__}"
        for m in members if all(offered) else ():
            want = list(inspect.signature(getattr(proto, m)).parameters)
            assert list(inspect.signature(getattr(cls, m)).parameters) == want, f"{module}.{m}"


def test_every_concrete_method_in_the_package_is_in_a_method_module():
    import pkgutil

    for info in pkgutil.iter_modules([str(FOLDER)]):
        if _method_classes(info.name):
            assert info.name in MODULES, f"engine/methods/{info.name}.py has a Method but no create()"
