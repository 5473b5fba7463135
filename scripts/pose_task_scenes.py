"""Write the pose-mode benchmark's tasks as one-key scenes (``assets/scenes/pose_tasks``).

Each task of ``engine/authoring/pose_task_table.py`` becomes ``<task>.json``: one frame,
one key whose targets are the task's goals (placed from the character's neutral pose, as
the benchmark places them), default character and pose options. ``bench --pose-tasks``
bakes them (the ``bake`` rows), and ``dragposer-studio bake`` takes them as they are:

    PYTHONPATH=. python scripts/pose_task_scenes.py [OUT_DIR]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from engine.atomic import write_text
from engine.authoring.document import authoring_to_dict
from engine.authoring.pose_task_table import TASKS
from engine.authoring.pose_tasks import TASK_SCENES, task_scene
from engine.models import load_default_models


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else TASK_SCENES
    out.mkdir(parents=True, exist_ok=True)
    vae = load_default_models().vae
    for task in TASKS:
        path = out / f"{task.name}.json"
        doc = authoring_to_dict(task_scene(task, vae))
        del doc["settings"], doc["constraints"]  # the defaults and none: a scene as a user writes it
        keys = doc.pop("keys")
        text = json.dumps(doc, indent=1)[:-2] + ',\n "keys": [\n'
        text += ",\n".join(f"  {json.dumps(k)}" for k in keys) + "\n ]\n}\n"
        write_text(path, text)
        print(f"{path}: {task.description}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
