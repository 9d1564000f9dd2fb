"""The submissions folder, read without trusting it: one bad entry costs only its student's marks.

Only directories are student folders and only regular files are notebooks: a symbolic link,
a FIFO, a device or a directory named like a notebook is never opened (its student gets 0 and
the reason). A notebook is read with O_NOFOLLOW | O_NONBLOCK, at most MAX_NOTEBOOK_BYTES, and
must be JSON nested at most MAX_DEPTH deep. Any file name (not UTF-8) and any text (lone
surrogates, control and bidi characters) is turned into printable UTF-8 before it reaches the
CSV, the feedback, its file name or the log (text()).
"""
import json
import os
import re
import stat

MAX_NOTEBOOK_BYTES = 20 << 20
MAX_DEPTH = 64  # a notebook nests about 6 deep; widget state a few more


# C0 and C1 controls (ESC, BEL, CR, NEL...), line and paragraph separators, Bidi_Control (U+202E)
UNSAFE = "\x00-\x09\x0b-\x1f\x7f-\x9f\u2028\u2029\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069"
_UNSAFE = {False: re.compile(f"[{UNSAFE}\n]"), True: re.compile(f"[{UNSAFE}]")}


def text(value, lines=False):
    """Printable UTF-8 of any str, to show on a terminal or in a file: undecodable bytes of a
    file name as \\xNN, lone surrogates as \\udNNN, control and bidi characters escaped
    (\\x1b, \\n, \\u202e), newlines kept only where `lines` (a multi-line text)."""
    value = str(value)
    try:
        value = os.fsencode(value).decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a lone surrogate that was never a byte
        value = value.encode("utf-8", "backslashreplace").decode("utf-8")
    return _UNSAFE[lines].sub(lambda m: m.group().encode("unicode_escape").decode(), value)


def _kind(mode):
    kinds = ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISDIR, "a directory"),
             (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"), (stat.S_ISCHR, "a device"),
             (stat.S_ISBLK, "a device"))
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def students(submissions):
    """[(name, folder path, problem)] sorted by name; problem: why the folder is not read
    (None: read it). Plain files at the top are not students; they are returned as
    ignored (a list of names)."""
    found, ignored = [], []
    with os.scandir(submissions) as entries:
        for entry in entries:
            if entry.name.startswith("."):
                continue
            mode = entry.stat(follow_symlinks=False).st_mode
            if stat.S_ISDIR(mode):
                found.append((entry.name, entry.path, None))
            elif stat.S_ISLNK(mode):
                found.append((entry.name, entry.path, "the student's folder is a symbolic "
                              "link: not read (only real folders are graded)"))
            else:
                ignored.append(entry.name)
    return sorted(found), sorted(ignored)


def notebooks(folder):
    """[(file name, path, problem)] of a student folder's *.ipynb entries, sorted."""
    found = []
    with os.scandir(folder) as entries:
        for entry in entries:
            if entry.name.startswith(".") or not entry.name.lower().endswith(".ipynb"):
                continue
            mode = entry.stat(follow_symlinks=False).st_mode
            problem = None if stat.S_ISREG(mode) else (
                f"not read: it is {_kind(mode)}, not a notebook file (only regular files are "
                "graded)")
            found.append((entry.name, entry.path, problem))
    return sorted(found)


def _too_deep(value, limit):
    stack = [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if depth > limit:
            return True
        if isinstance(item, dict):
            stack += [(v, depth + 1) for v in item.values()]
        elif isinstance(item, list):
            stack += [(v, depth + 1) for v in item]
    return False


def _read_bytes(path):
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_NOCTTY)
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):  # swapped since it was listed
            return None, f"not read: it is {_kind(info.st_mode)}, not a notebook file"
        chunks, size = [], 0  # read to one chunk past the limit, whatever st_size says
        while size <= MAX_NOTEBOOK_BYTES:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > MAX_NOTEBOOK_BYTES:
            return None, f"the notebook is larger than {MAX_NOTEBOOK_BYTES >> 20} MB"
        return b"".join(chunks), None
    finally:
        os.close(fd)


def read_notebook(path):
    """(the notebook as a dict with clean text, None) or (None, why it is not one)."""
    try:
        data, problem = _read_bytes(path)
    except OSError as exc:
        return None, f"could not read the notebook: {exc.strerror or exc}"
    if problem:
        return None, problem
    try:
        book = json.loads(data.decode("utf-8", errors="replace"))
    except RecursionError:
        return None, "could not read the notebook: its JSON is nested too deep"
    except ValueError as exc:
        return None, f"could not read the notebook: it is not JSON ({text(exc)[:200]})"
    if _too_deep(book, MAX_DEPTH):
        return None, f"could not read the notebook: its JSON is nested over {MAX_DEPTH} deep"
    # lone surrogates ("\ud800" in the JSON) become "?": every later step sees valid text
    book = json.loads(json.dumps(book, ensure_ascii=False).encode("utf-8", "replace"))
    if not isinstance(book, dict) or not isinstance(book.get("cells"), list):
        return None, "could not read the notebook: no list of cells in it"
    return book, None
