"""What a realtime DragPoser frame leaves out: the temporal predictor's conditioning
while the pose bank gives the prior (computed when the predictor needs it, the same
values as computed at once)."""

from __future__ import annotations

import pytest
import torch

import engine.methods.dragposer_root as roots_mod
from engine.kinematics.root import root_displacement
from engine.methods import driver, get_method
from engine.tracking import simulate


@pytest.fixture(scope="module")
def clip():
    from engine.cli.bench import DEFAULT_CLIP
    from engine.motion.retarget import load_motion

    return load_motion(DEFAULT_CLIP, max_frames=40)


def _run(clip, preset: str, monkeypatch, **settings):
    calls = []

    def counted(*args):
        calls.append(args)
        return root_displacement(*args)

    monkeypatch.setattr(roots_mod, "root_displacement", counted)
    method = get_method("dragposer", mode="realtime", iterations=3, **settings)
    if method.bank is None:
        pytest.skip("the shipped pose bank is not installed")
    driver.reset(method, clip.skeleton, clip.fps, reference=clip)
    tracking = simulate(clip, preset)
    for i in range(len(tracking)):
        driver.step(method, tracking.frame(i))
    return method, calls


def test_no_conditioning_is_computed_while_the_pose_bank_gives_the_prior(clip, monkeypatch):
    method, calls = _run(clip, "6", monkeypatch)
    assert method.priors.from_bank and method.priors.schedule.history
    assert calls == []


def test_the_predictor_gets_the_conditioning_it_got_when_it_was_computed_at_once(clip, monkeypatch):
    method, calls = _run(clip, "6", monkeypatch, prior="predictor")
    assert not method.priors.from_bank and calls  # the predictor ran on it
    lengths = []
    for _, cond in method.priors.schedule.history:
        roots, pos = cond.roots, cond.positions
        want = torch.cat((torch.stack([root_displacement(*r) for r in roots]).sum(0), pos[roots_mod._HEIGHT_IDX, 2]))
        assert torch.equal(cond(), want)
        lengths.append(len(roots))
    assert max(lengths) == method.settings.predictor_every  # summed over the last n frames
