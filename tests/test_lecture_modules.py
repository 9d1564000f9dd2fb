"""notebooks/README.md names, for each lecture, the modules whose code it shows: exactly the
files of the objects each notebook prints with inspect.getsource."""
import inspect
import json
import re
from pathlib import Path

import pytest

import ikteach as ik

ROOT = Path(__file__).resolve().parents[1]
TABLE = (ROOT / "notebooks" / "README.md").read_text()
LECTURES = sorted((ROOT / "notebooks").glob("[01][0-9]_*.ipynb"))


def listed(number):
    row = next(line for line in TABLE.splitlines() if line.startswith(f"| `{number}_"))
    return set(re.findall(r"`((?:core|characters|pictures)/[a-z_]+\.py)`", re.split(r"(?<!\\)\|", row)[3]))


def shown(path):
    code = "\n".join("".join(c["source"]) for c in json.loads(path.read_text())["cells"]
                     if c["cell_type"] == "code")
    names = {"ik": ik, "ws": ik.pictures.workspace_maps}
    files = set()
    for expression in re.findall(r"getsource\(([\w.]+)\)", code):
        obj = inspect.unwrap(eval(expression, names))  # noqa: S307  (our notebooks' own names)
        files.add(Path(inspect.getsourcefile(obj)).relative_to(ROOT / "ikteach").as_posix())
    return files


@pytest.mark.parametrize("path", LECTURES, ids=lambda p: p.name[:2])
def test_the_table_names_the_modules_each_lecture_shows(path):
    assert listed(path.name[:2]) == shown(path)
