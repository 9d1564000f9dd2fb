"""Every command the guides (docs/*.md) and the README show names something real, and the
cheap ones run: make targets exist, `ikteach` sub-commands answer --help, `python -m` modules
import, pip extras exist, and every repository path they name is there. So the guides cannot
rot silently when a target, a command or a file is renamed."""
import importlib.util
import re
import shlex
import subprocess
import sys
import tomllib
from functools import cache
from pathlib import Path

import pytest

from ikteach.course import cli

ROOT = Path(__file__).resolve().parents[1]
GUIDES = sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md"]
INLINE = re.compile(r"`((?:make|ikteach|\.venv/bin/ikteach|\.venv/bin/python|python3?) [^`]+)`")
# Other people's tools a guide may show (not ours to test): the first word of such a command.
EXTERNAL = {"conda", "jupyter", "pip", "docker", "sudo", "apt-get", "."}
# Paths a guide names that a command makes (not in the repository).
MADE = ("build/", ".venv", "feedback/", "out/", "submissions", "grades.csv", "copy.bvh",
        "results.json")
# A guide may name a file inside the folder it is talking about.
FOLDERS = [ROOT / f for f in ("", "docs", "binder", "ikteach", "ikteach/course",
                              "ikteach/characters", "ikteach/course/grading", "notebooks",
                              "tests/submissions")]
MIME = ("image/", "text/", "application/")
PATH = re.compile(r"`((?:[\w.-]+/)+[\w.-]*|[\w-]+\.(?:py|md|toml|yml|txt|json|cfg|lock))`")


def commands(path):
    """(command, line number) for every shell line of the file's bash blocks and inline code."""
    text, out = path.read_text(encoding="utf-8"), []
    for block in re.finditer(r"```bash\n(.*?)```", text, re.S):
        start = text[: block.start()].count("\n") + 2
        pending = ""
        for offset, line in enumerate(block.group(1).splitlines()):
            line = pending + " " + re.sub(r"\s+#[^'\"]*$", "", line).strip().rstrip("\\")
            try:  # a command continues while a quote is open or a line ends with a backslash
                shlex.split(line)
            except ValueError:
                pending = line
                continue
            pending = ""
            if line.strip() and not line.strip().startswith("#") and not block.group(1).splitlines()[offset].rstrip().endswith("\\"):
                out.append((line.strip(), start + offset))
            elif block.group(1).splitlines()[offset].rstrip().endswith("\\"):
                pending = line
    for match in INLINE.finditer(text):
        out.append((match.group(1), text[: match.start()].count("\n") + 1))
    return out


@cache
def make_targets():
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    variables = dict(re.findall(r"^(\w+)\s*[:?]?=\s*(.*?)\s*$", makefile, re.M))
    targets = set()
    for target in re.findall(r"^([\w.$()/-]+):", makefile, re.M):
        for _ in range(3):  # $(STAMP) -> $(VENV)/.installed-stamp -> .venv/.installed-stamp
            target = re.sub(r"\$\((\w+)\)", lambda m: variables.get(m.group(1), ""), target)
        targets.add(target)
    return targets


@cache
def extras():
    return set(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"])


@cache
def help_runs(sub):
    out = subprocess.run([sys.executable, "-m", "ikteach.course.cli", sub, "--help"],
                         capture_output=True, text=True, cwd=ROOT, timeout=120)
    return out.returncode == 0 and "usage:" in out.stdout


def problems(command):
    """What is wrong with one command line (empty when it names only real things)."""
    words = shlex.split(command.replace("[", "").replace("]", ""))
    for part in " ".join(words).split("&&"):
        words = part.split()
        first, rest = words[0], words[1:]
        if first == "make":
            targets = [w for w in rest if "=" not in w and not w.startswith("-")]
            yield from (f"no make target {t!r}" for t in targets if t not in make_targets())
        elif first in ("ikteach", ".venv/bin/ikteach"):
            sub = rest[0] if rest else "--help"
            if sub != "--help" and (sub not in cli.COMMANDS or not help_runs(sub)):
                yield f"no ikteach command {sub!r}"
            if sub == "exercises" and rest[1:2] != ["build"]:
                yield "ikteach exercises: expected `build`"
        elif first in ("python", "python3", ".venv/bin/python") and rest[0].endswith(".py"):
            if not (ROOT / rest[0]).is_file():
                yield f"no script {rest[0]!r}"
        elif first in ("python", "python3", ".venv/bin/python") and rest[:1] == ["-m"]:
            if importlib.util.find_spec(rest[1]) is None:
                yield f"no module {rest[1]!r}"
        elif first == "pip" and rest[:2] == ["install", "-e"]:
            wanted = set(re.findall(r"\w+", re.sub(r"^\.", "", rest[2]))) - {""}
            yield from (f"no extra {e!r}" for e in wanted if e not in extras())
        elif first not in EXTERNAL:
            yield f"unknown tool {first!r}"


CASES = [(path.relative_to(ROOT).as_posix(), line, command)
         for path in GUIDES for command, line in commands(path)]


@pytest.mark.parametrize("where, line, command", CASES,
                         ids=[f"{w}:{n}" for w, n, _ in CASES])
def test_a_guide_command_names_real_things(where, line, command):
    assert list(problems(command)) == [], f"{where}:{line}: {command}"


def test_the_guides_show_the_commands_a_lecturer_needs():
    shown = {c for _, _, c in CASES}
    for needed in ("make lab", "make test", "make site", "make slides", "make header",
                   "make lock-upgrade", "make exercises"):
        assert any(c.startswith(needed) for c in shown), needed
    assert any("ikteach grade" in c for c in shown)


def test_the_check_catches_a_renamed_target_or_command():
    assert list(problems("make sitee")) == ["no make target 'sitee'"]
    assert list(problems("ikteach gradee x --out y")) == ["no ikteach command 'gradee'"]
    assert list(problems("python -m ikteach.no_such_module")) == ["no module 'ikteach.no_such_module'"]


@pytest.mark.parametrize("path", GUIDES, ids=lambda p: p.name)
def test_every_repository_path_a_guide_names_exists(path):
    text = path.read_text(encoding="utf-8")
    missing = []
    for match in PATH.finditer(text):
        name = match.group(1)
        if name.startswith(MADE + MIME) or "NN" in name or "<" in name or name.startswith(("http", "~", "$")):
            continue
        candidates = [folder / name for folder in FOLDERS]
        if not any(c.exists() for c in candidates):
            missing.append(name)
    assert missing == []


def test_guide_links_point_at_files():
    for path in GUIDES:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", path.read_text(encoding="utf-8")):
            if not re.match(r"[a-z]+:", target):
                assert (path.parent / target).exists(), f"{path.name}: {target}"


def unfinished_paragraphs(text):
    """The last lines of prose paragraphs that end without closing punctuation: a sentence cut
    off (a paragraph that introduces a code block or a table may end as it likes)."""
    blocks = [b.strip("\n") for b in re.split(r"\n[ \t]*\n", text)]
    cut, fence = [], False
    for block, after in zip(blocks, blocks[1:] + [""]):
        if block.count("```") % 2:
            fence = not fence
        if fence or "```" in block or not block.strip():
            continue
        last = block.splitlines()[-1].strip()
        if last.startswith(("|", "#", "<", "![", "[")) or after.lstrip().startswith(("```", "|")) \
                or after.startswith("    "):
            continue
        if not re.search(r"[.:;!?)`*>\]]$", last):
            cut.append(last)
    return cut


@pytest.mark.parametrize("guide", GUIDES + [ROOT / "notebooks" / "README.md"], ids=lambda p: p.name)
def test_no_guide_stops_mid_sentence(guide):
    assert unfinished_paragraphs(guide.read_text(encoding="utf-8")) == []


def test_a_sentence_cut_off_is_caught():
    assert unfinished_paragraphs("Say what is wrong (NaN near a\n\nNext paragraph.\n") == ["Say what is wrong (NaN near a"]
    assert unfinished_paragraphs("Run\n\n```\nmake site\n```\n") == []
