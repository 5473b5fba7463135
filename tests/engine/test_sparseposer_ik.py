"""SparsePoser's limb networks trained alone on the frozen generator's realtime output."""

from __future__ import annotations

import pytest
import torch

from engine.config import load_config
from engine.errors import UserError
from engine.models.loading import load_sparseposer
from engine.models.sparseposer import SparsePoser, SparsePoserConfig
from engine.training.data import load_split
from engine.training.sparseposer import SparsePoserTrainConfig, train_sparseposer
from engine.training.sparseposer_ik import realtime_outputs
from tests.engine.test_sparseposer import TINY
from tests.engine.test_training import tiny_data  # noqa: F401  (fixture: a tiny prepared folder)


def test_realtime_outputs_are_the_last_frame_of_each_window_with_the_first_frame_repeated(tiny_data):  # noqa: F811
    torch.manual_seed(0)
    model = SparsePoser(SparsePoserConfig(window=32, channels=(4, 6, 8), ik_hidden=16)).eval()
    data = load_split(tiny_data, "val")
    got = realtime_outputs(model, data, chunk=7, progress=False)  # pieces that start inside clips
    torch.testing.assert_close(realtime_outputs(model, data, progress=False), got, atol=1e-6, rtol=0)
    first = {}
    with torch.no_grad():
        for i in range(0, len(data), 5):
            c = int(data.clip[i])
            start = first.setdefault(c, int(torch.nonzero(data.clip == c)[0]))
            idx = torch.arange(i - 31, i + 1).clamp_min(start)  # the clip's first frame repeated before it
            want = model.generate(data.dq[idx][None], data.offsets[i : i + 1])[0, -1]
            torch.testing.assert_close(got[i], want, atol=2e-5, rtol=0)


def test_limb_networks_alone_start_from_init_and_leave_the_generator(tiny_data, tmp_path):  # noqa: F811
    tiny = [s for s in TINY if not s.startswith("window")] + ["window=32"]
    meta = train_sparseposer(
        tiny_data, tmp_path / "joint", load_config(SparsePoserTrainConfig, None, tiny, epochs=1), progress=False
    )
    assert meta["finished"]
    init = tmp_path / "joint" / "sparseposer.pt"
    cfg = load_config(SparsePoserTrainConfig, None, tiny + ["train_generator=false", f"init={init}"], epochs=2)
    meta = train_sparseposer(tiny_data, tmp_path / "ik", cfg, progress=False)
    assert meta["finished"] and meta["epochs"] == 2
    before, _ = load_sparseposer(init)
    after, _ = load_sparseposer(tmp_path / "ik" / "sparseposer.pt")
    a, b = before.state_dict(), after.state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a if k.startswith("generator."))
    assert not all(torch.equal(a[k], b[k]) for k in a if k.startswith("ik."))
    with pytest.raises(UserError, match="init"):
        no_init = load_config(SparsePoserTrainConfig, None, tiny + ["train_generator=false"])
        train_sparseposer(tiny_data, tmp_path / "no_init", no_init, progress=False)
