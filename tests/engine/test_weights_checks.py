"""Weights files that are not what they claim: one line naming the file and field, no
library warning, and no model memory before the config and the weights agree."""

from __future__ import annotations

import dataclasses
import os
import pickle
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
import torch

from engine.errors import ModelFileError
from engine.models.loading import load_predictor, load_rpm, load_sparseposer, load_vae
from engine.models.predictor import PredictorConfig
from engine.models.rpm import RPMConfig
from engine.models.sparseposer import SparsePoserConfig
from engine.models.vae import VAEConfig
from engine.models.weights_check import CONFIGS

REPO = Path(__file__).resolve().parents[2]
EX = REPO / "assets" / "clips" / "example.bvh"
SHIPPED = {kind: REPO / "assets" / "models" / f"{kind}.pt" for kind in CONFIGS}
LOADERS = {"vae": load_vae, "predictor": load_predictor, "sparseposer": load_sparseposer, "rpm": load_rpm}
CLASSES = {"vae": VAEConfig, "predictor": PredictorConfig, "sparseposer": SparsePoserConfig, "rpm": RPMConfig}


def _payload(kind: str) -> dict:
    return torch.load(SHIPPED[kind], map_location="cpu", weights_only=True)


def _cli(*argv: object, limit_bytes: int | None = None) -> subprocess.CompletedProcess:
    """The real command line in a child process (its stderr is what a user sees)."""
    pre = ""
    if limit_bytes:  # a bounded address space: a loader that allocates for nothing fails, not the machine
        pre = f"import resource; resource.setrlimit(resource.RLIMIT_AS, ({limit_bytes}, {limit_bytes}))\n"
    # The peak is read from VmHWM, which exec resets: ru_maxrss would carry the pytest
    # parent's resident size over the fork into the child's figure.
    code = pre + (
        "import re, sys\nfrom engine.cli.main import main\ntry:\n    rc = main(sys.argv[1:])\n"
        "finally:\n    hwm = re.search(r'VmHWM:\\s+(\\d+)', open('/proc/self/status').read()).group(1)\n"
        "    print('maxrss_kb', hwm)\n"
        "sys.exit(rc)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, argv)], capture_output=True, text=True, env=env, timeout=600
    )


def _one_line(proc: subprocess.CompletedProcess, *needles: str) -> str:
    lines = [s for s in proc.stderr.splitlines() if s.strip()]
    assert proc.returncode == 2, proc.stderr[-1500:]
    assert len(lines) == 1, proc.stderr[-1500:]
    for n in needles:
        assert n in lines[0], lines[0]
    return lines[0]


def test_a_text_file_as_weights_is_one_line(tmp_path):
    for text in ("hello world\n", "notes: remember to train\n", "e"):
        notes = tmp_path / "notes.txt"
        notes.write_text(text)
        with pytest.raises(ModelFileError, match=r"notes\.txt: not a torch weights file: it is a text file"):
            load_vae(notes)
    (tmp_path / "empty.pt").write_bytes(b"")
    with pytest.raises(ModelFileError, match="empty"):
        load_vae(tmp_path / "empty.pt")


def test_meta_that_is_not_a_dict_names_the_field(tmp_path):
    payload = _payload("vae")
    payload["meta"] = "hello"
    torch.save(payload, tmp_path / "meta.pt")
    with pytest.raises(ModelFileError, match=r"meta\.pt: field 'meta' must be a dict, got str"):
        load_vae(tmp_path / "meta.pt")


def test_a_plain_pickle_gives_only_our_line(tmp_path):
    with open(tmp_path / "plain.pkl", "wb") as fh:
        pickle.dump({"kind": "vae", "state_dict": {}}, fh, protocol=4)
    proc = _cli("reconstruct", EX, "--out", tmp_path / "o.bvh", "--max-frames", "2", "--vae", tmp_path / "plain.pkl")
    _one_line(proc, "plain.pkl", "plain pickle")
    assert "Warning" not in proc.stderr and not (tmp_path / "o.bvh").exists()


def test_a_zip_with_a_newer_pickle_protocol_warns_nothing(tmp_path):
    torch.save(_payload("vae"), tmp_path / "p4.pt", pickle_protocol=4)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(ModelFileError, match=r"p4\.pt: refused: .*pickle instruction 149 \(FRAME\)"):
            load_vae(tmp_path / "p4.pt")
    assert [str(w.message) for w in seen] == []


def test_a_huge_config_in_a_tiny_file_allocates_nothing(tmp_path):
    """16 billion values described in 1 kB: refused with the config named, in the memory of
    an idle process (under a 4 GB address-space cap that the unchecked loader hits)."""
    payload = {
        "kind": "vae",
        "format_version": 1,
        "state_dict": {},
        "meta": {},
        "config": {"latent": 24, "channels": [4000, 4000, 4000, 4000]},
    }
    torch.save(payload, tmp_path / "big.pt")
    assert (tmp_path / "big.pt").stat().st_size < 2000
    proc = _cli(
        "reconstruct",
        EX,
        "--out",
        tmp_path / "o.bvh",
        "--max-frames",
        "2",
        "--vae",
        tmp_path / "big.pt",
        limit_bytes=4 << 30,
    )
    _one_line(proc, "big.pt", "channels = [4000, 4000, 4000, 4000]", "do not fit")
    maxrss_mb = int(proc.stdout.split("maxrss_kb")[1].split()[0]) / 1024
    assert maxrss_mb < 1000, maxrss_mb  # importing torch and the CLI takes about 250 MB


def test_views_of_one_storage_cannot_make_a_model_bigger_than_its_file(tmp_path):
    payload = _payload("rpm")
    state = payload["state_dict"]
    flat = torch.zeros(max(t.numel() for t in state.values()))
    payload["state_dict"] = {k: flat[: t.numel()].view(t.shape) for k, t in state.items()}
    torch.save(payload, tmp_path / "shared.pt")
    with pytest.raises(ModelFileError, match=r"shared\.pt: config \(past_inputs = .*describes a model of"):
        load_rpm(tmp_path / "shared.pt")


def test_every_config_field_has_a_bound():
    for kind, (schema, channels) in CONFIGS.items():
        names = {f.name for f in dataclasses.fields(CLASSES[kind])}
        assert names == set(schema) | ({"channels"} if channels else set()), kind


BAD_CONFIGS = [
    # kind, config change, words of the message
    ("vae", {"channels": [32, 48, 64]}, "channels = [32, 48, 64] is not a list of 4"),
    ("vae", {"channels": [32, 48, 5000, 96]}, "channels[2] = 5000 is out of range"),
    ("vae", {"latent": 0}, "latent = 0 is out of range; allowed: a whole number in [1, 1024]"),
    ("vae", {"colour": "red"}, "unknown field 'colour'"),
    ("predictor", {"heads": 5}, "d_model = 48, heads = 5: must be d_model a multiple of heads"),
    ("predictor", {"feedforward": 10**9}, "feedforward = 1000000000 is out of range"),
    ("sparseposer", {"window": 12}, "window = 12: must be a multiple of 8"),
    ("sparseposer", {"kernel": 4}, "kernel = 4: must be odd"),
    ("sparseposer", {"channels": [16, 32, 0]}, "channels[2] = 0 is out of range"),
    ("rpm", {"past_poses": -1}, "past_poses = -1 is out of range"),
    ("rpm", {"hidden": 2.5}, "hidden = 2.5 is not a whole number"),
]


@pytest.mark.parametrize("kind, change, words", BAD_CONFIGS)
def test_bad_configs_name_the_field(tmp_path, kind, change, words):
    payload = _payload(kind)
    payload["config"] = {**payload["config"], **change}
    torch.save(payload, tmp_path / f"{kind}.pt")
    with pytest.raises(ModelFileError) as err:
        LOADERS[kind](tmp_path / f"{kind}.pt")
    text = str(err.value)
    assert text.startswith(f"{tmp_path / kind}.pt: config: ") and words in text, text
    assert "\n" not in text


def test_state_dict_entries_must_match_in_name_shape_and_dtype(tmp_path):
    payload = _payload("predictor")
    key = next(iter(payload["state_dict"]))
    cases = [
        ({key: payload["state_dict"][key].double()}, f"state_dict['{key}'] is torch.float64"),
        ({key: "text"}, f"state_dict['{key}'] is a str, expected a tensor"),
        ({key: torch.zeros(3)}, f"size mismatch for {key}"),
        ({"extra.weight": torch.zeros(1)}, 'Unexpected key(s) in state_dict: "extra.weight"'),
    ]
    for change, words in cases:
        bad = {**payload, "state_dict": {**payload["state_dict"], **change}}
        torch.save(bad, tmp_path / "p.pt")
        with pytest.raises(ModelFileError) as err:
            load_predictor(tmp_path / "p.pt")
        assert words in str(err.value) and "\n" not in str(err.value), str(err.value)


@pytest.mark.parametrize("kind", list(CONFIGS))
def test_the_shipped_weights_pass_every_check(kind):
    model, meta = LOADERS[kind](SHIPPED[kind])
    assert isinstance(meta, dict) and not model.training
    assert all(p.device.type == "cpu" for p in model.parameters())
