"""The Flamenco job type (scripts/flamenco/thinburn_bake.js) compiled with a stand-in `author`
API in Node.js: one chained task per sheet, each running the headless bake command line."""
from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

JOB = Path(__file__).resolve().parents[1] / "scripts" / "flamenco" / "thinburn_bake.js"

HARNESS = r"""
const fs = require("fs");
const tasks = [];
const author = {
  Task: (name, type) => {
    const t = {name, type, commands: [], deps: []};
    t.addCommand = (c) => t.commands.push(c);
    t.addDependency = (d) => t.deps.push(d.name);
    return t;
  },
  Command: (name, params) => ({name, params}),
};
eval(fs.readFileSync(process.argv[1], "utf8") + "\n;globalThis.JOB_TYPE = JOB_TYPE; globalThis.compileJob = compileJob;");
const job = {settings: JSON.parse(process.argv[2]), addTask: (t) => tasks.push(t)};
compileJob(job);
console.log(JSON.stringify({keys: JOB_TYPE.settings.map((s) => s.key),
  tasks: tasks.map((t) => ({name: t.name, deps: t.deps, commands: t.commands}))}));
"""


def _compile(settings):
    node = shutil.which("node") or shutil.which("nodejs")
    if node is None:
        pytest.skip("Node.js is not installed")
    out = subprocess.run([node, "-e", HARNESS, str(JOB), json.dumps(settings)], capture_output=True,
                         text=True, timeout=60)
    return out


def test_one_chained_headless_task_per_sheet():
    out = _compile({"sheets": "Sheet, Curtain", "addon_module": "thinburn_addon", "usd_dir": "",
                    "blendfile": "/farm/shot.blend"})
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert {"sheets", "addon_module", "usd_dir", "blendfile"} <= set(got["keys"])
    tasks = got["tasks"]
    assert [t["name"] for t in tasks] == ["thinburn-bake-Sheet", "thinburn-bake-Curtain"]
    assert tasks[0]["deps"] == [] and tasks[1]["deps"] == ["thinburn-bake-Sheet"]
    cmd = tasks[1]["commands"][0]
    assert cmd["name"] == "blender-render"
    assert cmd["params"]["blendfile"] == "/farm/shot.blend"
    assert cmd["params"]["args"] == ["--python-expr", "import thinburn_addon.headless as h; h.main()",
                                     "--", "--object", "Curtain"]


def test_usd_folder_and_no_sheets():
    out = _compile({"sheets": "Sheet", "addon_module": "bl_ext.user_default.thinburn",
                    "usd_dir": "/farm/usd", "blendfile": "/farm/shot.blend"})
    args = json.loads(out.stdout)["tasks"][0]["commands"][0]["params"]["args"]
    assert args[-2:] == ["--usd", "/farm/usd"] and "bl_ext.user_default.thinburn.headless" in args[1]
    out = _compile({"sheets": " ", "addon_module": "x", "usd_dir": "", "blendfile": "/f.blend"})
    assert out.returncode != 0 and "no sheets to bake" in out.stderr
