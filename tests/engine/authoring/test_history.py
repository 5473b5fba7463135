"""The undo history both windows use: edits with their own ``put``, groups as one step."""

from __future__ import annotations

from engine.authoring.history import Edit, History


class Model:
    def __init__(self) -> None:
        self.parts = {"a": 0, "b": 0}

    def setter(self, name):
        return lambda value: self.parts.__setitem__(name, value)


def test_edits_put_their_own_part_back_and_merge_while_a_drag_goes_on():
    m, changes = Model(), []
    h = History(m, lambda: changes.append(1))
    for v in (1, 2, 3):  # a drag: one step
        before, m.parts["a"] = m.parts["a"], v
        h.push(Edit("move a", before, v, ("part", "a", "value"), put=m.setter("a")))
    m.parts["b"] = 5
    h.push(Edit("set b", 0, 5, None, put=m.setter("b")))
    assert h.texts() == ["move a", "set b"] and len(changes) == 4
    h.undo()
    h.undo()
    assert m.parts == {"a": 0, "b": 0}
    h.redo()
    assert m.parts == {"a": 3, "b": 0} and h.undo_text() == "move a" and h.redo_text() == "set b"


def test_a_group_is_one_step_undone_in_reverse_and_an_empty_group_is_none():
    m, order = Model(), []

    def put(name):
        def f(value):
            order.append((name, value))
            m.parts[name] = value

        return f

    h = History(m)
    with h.group("load scene"):
        m.parts["a"] = 1
        h.push(Edit("set a", 0, 1, None, put=put("a")))
        with h.group("inner"):  # joins the outer group
            m.parts["b"] = 2
            h.push(Edit("set b", 0, 2, None, put=put("b")))
    with h.group("nothing"):
        pass
    assert h.texts() == ["load scene"] and h.can_undo()
    h.undo()
    assert m.parts == {"a": 0, "b": 0} and order == [("b", 0), ("a", 0)]
    h.redo()
    assert m.parts == {"a": 1, "b": 2} and order[2:] == [("a", 1), ("b", 2)]
    assert not h.can_redo()


def test_a_step_that_did_not_happen_is_discarded_and_the_saved_state_is_clean_again():
    m = Model()
    h = History(m)
    m.parts["a"] = 1
    h.push(Edit("set a", 0, 1, None, put=m.setter("a")))
    h.set_clean()
    refused = Edit("switch b", 0, 7, None, put=m.setter("b"))  # recorded, then refused
    h.push(refused)
    m.parts["a"] = 2
    h.push(Edit("set a again", 1, 2, None, put=m.setter("a")))
    assert not h.is_clean()
    assert h.discard(refused) and not h.discard(refused)
    assert h.texts() == ["set a", "set a again"] and h.undo_text() == "set a again"
    h.undo()
    assert h.is_clean() and m.parts == {"a": 1, "b": 0}
    h.undo()
    assert m.parts == {"a": 0, "b": 0} and not h.can_undo()


def test_a_step_discarded_from_a_group_leaves_the_rest_of_the_group_and_an_emptied_group_goes():
    m = Model()
    h = History(m)
    refused = Edit("switch b", 0, 7, None, put=m.setter("b"))
    with h.group("load scene"):
        m.parts["a"] = 1
        h.push(Edit("set a", 0, 1, None, put=m.setter("a")))
        h.push(refused)
    assert h.discard(refused) and h.texts() == ["load scene"]
    h.undo()
    assert m.parts == {"a": 0, "b": 0}
    alone = Edit("switch b", 0, 7, None, put=m.setter("b"))
    with h.group("only a switch"):
        h.push(alone)
    assert h.texts() == ["only a switch"]  # the undone "load scene" is dropped by the new step
    assert h.discard(alone) and h.texts() == [] and h.is_clean()
