"""The Python readers follow the shard schema: every array name that scripts/hypershape_data.py
and scripts/hypershape_torch.py look up in a shape group (a string literal used as a key, or a
name of the per-load-case tables _LOAD_SCALARS / _LOAD_COUNTS under "loads/") is a row of
docs/FORMAT.md's shard table, which tests/factory/test_dataset_schema.cpp in turn holds equal
to the writer's table (factory::shard_schema). A reader that asks for a renamed or removed array
fails here, not on a user's dataset. Needs HYPERSHAPE_SOURCE_DIR (set by CTest)."""
import ast
import os
import re
import sys

src = os.environ["HYPERSHAPE_SOURCE_DIR"]
failures = []


def schema_names():
    """The names of FORMAT.md's shard table (rows '| `name`[, `name`...] | ...' after '### A shard')."""
    text = open(os.path.join(src, "docs", "FORMAT.md"), encoding="utf-8").read()
    shard = text[text.index("### A shard"):]
    shard = shard[:shard.index("\n### ", 1)]
    names = set()
    for first_cell in re.findall(r"^\| (`[^|]+`) \|", shard, re.M):  # a row may list several
        names.update(re.findall(r"`([^`]+)`", first_cell))
    assert len(names) > 20, f"FORMAT.md's shard table has only {len(names)} rows: parse error?"
    return names


def matches(name, names):
    """Exact, or a table pattern such as params/<label>/<key> or loads/<channel>."""
    if name in names:
        return True
    for pattern in names:
        if "<" in pattern:
            rx = "^" + re.sub(r"<[^>]+>", r"[^/]+", re.escape(pattern).replace(r"\<", "<").replace(r"\>", ">")) + "$"
            if re.match(rx, name):
                return True
    return False


def looked_up_names(path):
    """String constants used as subscripts g["..."] (array lookups) and the loads/ tables."""
    tree = ast.parse(open(path, encoding="utf-8").read(), path)
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant) \
                and isinstance(node.slice.value, str):
            found.add(node.slice.value)
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id in ("_LOAD_SCALARS", "_LOAD_COUNTS")
                                                for t in node.targets):
            found.update("loads/" + e.value for e in node.value.elts)
    return found


names = schema_names()
# Subscripts that are not shard arrays: dict keys of manifests, stats, attributes, configs.
groups = ("nodes", "cells", "dirichlet_mask", "neumann_mask")
prefixes = ("loads/", "grid/", "point_cloud/", "params/")
checked = 0
for script in ("hypershape_data.py", "hypershape_torch.py"):
    for name in sorted(looked_up_names(os.path.join(src, "scripts", script))):
        if name not in groups and not name.startswith(prefixes):
            continue
        checked += 1
        if not matches(name, names):
            failures.append(f"{script} reads '{name}', which docs/FORMAT.md's shard table does not list")

if checked < 8:
    failures.append(f"only {checked} array names found in the readers: the scan no longer sees their lookups")
for f in failures:
    print("FAIL:", f)
print(f"{checked} array names the readers look up, checked against {len(names)} rows of the shard table")
sys.exit(1 if failures else 0)
