"""MethodSet builds each method once per selection and reports a failing build once."""

from __future__ import annotations

from collections import Counter

from engine.studio.clip_source import ClipSource
from engine.studio.method_set import MethodSet
from tests.stand_ins import RestPoseMethod


def _counting_set():
    built: Counter[str] = Counter()
    problems: list[str] = []

    def factory(name):
        built[name] += 1
        if name == "broken":
            raise ValueError("assets/models/vae.pt: not a weights file")
        return RestPoseMethod()

    return MethodSet(factory, problems.append), built, problems


def test_a_selection_builds_the_method_once_and_a_ghost_edit_keeps_it(synthetic_motion):
    methods, built, problems = _counting_set()
    source = ClipSource(synthetic_motion)
    assert methods.select("dragposer", ())
    methods.reset(source)  # what the engine thread does after every selection
    assert built == {"dragposer": 1}
    shown = methods.method
    assert methods.select("dragposer", ("ik",))  # ticking a ghost
    methods.reset(source)
    assert methods.select("dragposer", ("ik", "rpm"))
    methods.reset(source)
    assert built == {"dragposer": 1, "ik": 1, "rpm": 1}
    assert methods.method is shown and set(methods.ghosts) == {"ik", "rpm"}
    methods.reset(source)  # a new clip, a loop: resets, never builds
    assert methods.select("ik", ("rpm",))  # another method: built anew, the ghost kept
    methods.reset(source)
    assert built == {"dragposer": 1, "ik": 2, "rpm": 1} and not problems


def test_a_failing_first_build_is_reported_once_and_tried_again_with_the_next_clip(synthetic_motion):
    methods, built, problems = _counting_set()
    source = ClipSource(synthetic_motion)
    assert methods.select("broken", ())  # nothing ran before: the selection stands
    methods.reset(source)
    assert built == {"broken": 1} and len(problems) == 1 and "vae.pt" in problems[0]
    methods.reset(source)  # e.g. the user opens another clip
    assert built == {"broken": 2} and methods.method is None


def test_a_prepared_method_serves_the_first_selection_only(synthetic_motion):
    methods, built, problems = _counting_set()
    source = ClipSource(synthetic_motion)
    methods.prepare("dragposer")  # the engine process, before any command
    assert built == {"dragposer": 1}
    assert methods.select("dragposer", ())
    methods.reset(source)
    assert built == {"dragposer": 1}  # the prepared one, not a second build
    assert methods.select("ik", ())
    assert methods.select("dragposer", ())  # selected again: a new method, as without prepare
    assert built == {"dragposer": 2, "ik": 1} and not problems


def test_a_failing_prepare_is_reported_by_the_selection_that_builds_again(synthetic_motion):
    methods, built, problems = _counting_set()
    methods.prepare("broken")
    assert built == {"broken": 1} and not problems  # nothing asked for it yet
    assert methods.select("broken", ())
    assert built == {"broken": 2} and len(problems) == 1 and "vae.pt" in problems[0]


def test_a_ghost_that_cannot_run_from_the_trackers_reports_no_edit_problems(synthetic_motion):
    """SparsePoser needs preset 6: under 3-head-hands its 'ignores constraints' would hide,
    in the status bar, why it draws nothing (its row in the Optimizer tab says that)."""
    from engine.editing.constraint_list import ConstraintList
    from engine.tracking import PRESET_SENSORS

    methods, built, problems = _counting_set()
    scene = ConstraintList()
    scene.add("floor", name="floor")
    methods.set_sensors(PRESET_SENSORS["3-head-hands"])
    methods.set_constraints(tuple(scene))
    assert methods.select("dragposer", ())
    methods.set_ghosts(("sparseposer", "autoencoder"), ClipSource(synthetic_motion))
    assert set(methods.ghosts) == {"sparseposer", "autoencoder"} and built["dragposer"] == 1
    # the stand-in takes no constraints: said once, for the ghost that can run
    assert problems == [f"{methods.ghosts['autoencoder'].name} ignores constraints"]
