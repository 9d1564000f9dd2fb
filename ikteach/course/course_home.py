"""The course's public home, read from pyproject.toml: the one place that names it.

pyproject.toml holds the package name ([project] name), the repository's URL
([project.urls] Repository, a GitHub URL) and the branch ([tool.ikteach] branch). Everything
that points at the published course is derived here: the pip requirement Colab installs and
the Colab / Binder links and badges (see ikteach.notebook_header, which writes them).
"""
import re
from dataclasses import dataclass
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]
COLAB_BADGE = "https://colab.research.google.com/assets/colab-badge.svg"
BINDER_BADGE = "https://mybinder.org/badge_logo.svg"


@dataclass(frozen=True)
class Home:
    package: str      # e.g. "ikteach"
    repository: str   # e.g. "https://github.com/OWNER/NAME"
    branch: str       # e.g. "main"

    @property
    def github(self):
        """'OWNER/NAME' of the GitHub repository."""
        m = re.fullmatch(r"https://github\.com/([\w.-]+/[\w.-]+?)(?:\.git)?/?", self.repository)
        if not m:
            raise ValueError(f"repository: expected https://github.com/OWNER/NAME, "
                             f"got {self.repository!r}")
        return m.group(1)

    @property
    def requirement(self):
        """What Colab's first cell pip-installs: the package from the repository's branch."""
        return self.requirement_with()

    def requirement_with(self, extras=()):
        """The requirement with the package's extras, e.g. ikteach[scenes] @ git+..."""
        name = f"{self.package}[{','.join(extras)}]" if extras else self.package
        return f"{name} @ git+{self.repository}@{self.branch}"

    def colab_url(self, path):
        return f"https://colab.research.google.com/github/{self.github}/blob/{self.branch}/{path}"

    def binder_url(self, path):
        return f"https://mybinder.org/v2/gh/{self.github}/{self.branch}?urlpath=lab/tree/{path}"

    def badges(self, path):
        """Markdown: an 'Open in Colab' and a 'Binder' badge for a notebook path in the repo."""
        return (f"[![Open in Colab]({COLAB_BADGE})]({self.colab_url(path)}) "
                f"[![Binder]({BINDER_BADGE})]({self.binder_url(path)})")


BRANCH_LINE = re.compile(r'^(branch\s*=\s*)"[^"]*"', re.M)
REF = re.compile(r"[A-Za-z0-9][\w.-]*(/[\w.-]+)*")


def with_branch(text, ref):
    """pyproject.toml's text with [tool.ikteach] branch set to ref: a branch or a tag (a term's
    release, e.g. "v2026.1"), which Colab then installs from and the badges open."""
    if not REF.fullmatch(ref or "") or ".." in ref or ref.endswith((".", ".lock")):
        raise ValueError(f"ref: expected a git branch or tag name such as main or v2026.1, got {ref!r}")
    start = text.find("[tool.ikteach]")
    if start < 0:
        raise ValueError("pyproject.toml: expected a [tool.ikteach] table with branch = \"...\"")
    end = text.find("\n[", start + 1)
    table = text[start:end if end >= 0 else len(text)]
    if not BRANCH_LINE.search(table):
        raise ValueError("pyproject.toml: expected branch = \"...\" under [tool.ikteach]")
    new = BRANCH_LINE.sub(lambda m: f'{m.group(1)}"{ref}"', table, count=1)
    return text[:start] + new + text[start + len(table):]


def home(pyproject=ROOT / "pyproject.toml"):
    """The Home named by a pyproject.toml."""
    data = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))
    project = data["project"]
    urls = project.get("urls", {})
    if "Repository" not in urls:
        raise ValueError("pyproject.toml: expected [project.urls] Repository")
    branch = data.get("tool", {}).get("ikteach", {}).get("branch", "main")
    return Home(project["name"], urls["Repository"], branch)
