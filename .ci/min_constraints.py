"""Print a pip constraints file that pins every dependency of pyproject.toml (the package's
and its ``test`` extra's) to its declared lower bound: ``numpy>=1.26`` becomes
``numpy==1.26``. `.ci/run` installs towtank with it to prove the floors work together."""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

root = Path(__file__).resolve().parents[1]
project = tomllib.loads((root / "pyproject.toml").read_text())["project"]
deps = list(project["dependencies"])
for extra in project.get("optional-dependencies", {}).values():
    deps.extend(extra)
pins = {}
for dep in deps:
    m = re.fullmatch(r"\s*([A-Za-z0-9_.\-]+)\s*>=\s*([0-9][0-9A-Za-z.]*)\s*", dep)
    if m is None:
        sys.exit(f"{dep!r} has no plain lower bound (name>=version): give it one")
    name = m.group(1).lower()
    if name == "ruff":  # a linter: its version does not change what towtank computes
        continue
    pins[name] = m.group(2)
print("\n".join(f"{name}=={version}" for name, version in sorted(pins.items())))
