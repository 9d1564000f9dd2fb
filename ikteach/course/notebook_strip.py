"""Strip run noise from executed notebooks, so that re-running an unchanged notebook changes
nothing in git.

    python -m ikteach.notebook_strip NOTEBOOK...          # rewrite in place (make strip)
    python -m ikteach.notebook_strip --check NOTEBOOK...  # exit 1 and name the noisy ones

Noise is what differs between two runs of the same notebook with the same versions:
per-cell execution timestamps, saved widget state and the random widget model ids that
point into it, the kernel's exact Python version, Lab's view flags (collapsed, scrolled),
how a stream was split into outputs (merged into one per run of stdout/stderr), and the
random element ids of matplotlib's JavaScript animations (made stable here: a hash
of the animation's own HTML). Outputs that carry results are kept as they are.
"""
import argparse
import hashlib
import json
import re
import sys
from pathlib import Path

CELL_NOISE = ("execution", "ExecuteTime", "collapsed", "scrolled", "trusted")
WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
# matplotlib's to_jshtml names its elements _anim_img<uuid4 hex>, anim<uuid4 hex>, ...
UUID_HEX = re.compile(r"[0-9a-f]{12}4[0-9a-f]{3}[89ab][0-9a-f]{15}")


def _stable_ids(text):
    """Replace the random uuid4 hex ids in one HTML output by a hash of the output itself."""
    ids = list(dict.fromkeys(UUID_HEX.findall(text)))
    if not ids:
        return text
    blank = UUID_HEX.sub("", text)
    for k, old in enumerate(ids):
        new = hashlib.md5(f"{k}:{blank}".encode()).hexdigest()
        text = text.replace(old, new)
    return text


def _strip_output(output):
    data = output.get("data")
    if not data:
        return output
    if WIDGET_VIEW in data:
        del data[WIDGET_VIEW]
    if "text/html" in data:
        html = data["text/html"]
        joined = "".join(html) if isinstance(html, list) else html
        if "anim" in joined:
            stable = _stable_ids(joined)
            if stable != joined:
                data["text/html"] = stable.splitlines(keepends=True) if isinstance(html, list) else stable
    return output


def _merge_streams(outputs):
    """Consecutive stdout (or stderr) outputs as one: how a run splits them depends on timing."""
    merged = []
    for output in outputs:
        last = merged[-1] if merged else None
        if (last is not None and output.get("output_type") == "stream" == last.get("output_type")
                and output.get("name") == last.get("name")):
            text = "".join(last["text"]) + "".join(output["text"])
            last["text"] = text.splitlines(keepends=True)
        else:
            merged.append(output)
    return merged


def strip_notebook(nb):
    """Remove run noise from a notebook (a dict or nbformat node), in place; returns it."""
    meta = nb.get("metadata", {})
    meta.pop("widgets", None)
    meta.get("language_info", {}).pop("version", None)
    for cell in nb.get("cells", []):
        for key in CELL_NOISE:
            cell.get("metadata", {}).pop(key, None)
        cell.get("metadata", {}).get("jupyter", {}).pop("outputs_hidden", None)
        if cell.get("metadata", {}).get("jupyter") == {}:
            del cell["metadata"]["jupyter"]
        if cell.get("cell_type") == "code":
            cell["outputs"] = _merge_streams([_strip_output(o) for o in cell.get("outputs", [])])
    return nb


def noise(nb):
    """What strip_notebook would remove or change, as short strings (empty: clean)."""
    found = []
    meta = nb.get("metadata", {})
    if "widgets" in meta:
        found.append("saved widget state (metadata.widgets)")
    if "version" in meta.get("language_info", {}):
        found.append("kernel Python version (metadata.language_info.version)")
    for i, cell in enumerate(nb.get("cells", [])):
        keys = [k for k in CELL_NOISE if k in cell.get("metadata", {})]
        if keys:
            found.append(f"cell {i}: metadata {', '.join(keys)}")
        outputs = cell.get("outputs", [])
        if len(_merge_streams(json.loads(json.dumps(outputs)))) != len(outputs):
            found.append(f"cell {i}: one stream split into several outputs")
        for output in outputs:
            before = json.dumps(output, sort_keys=True)
            after = json.dumps(_strip_output(json.loads(before)), sort_keys=True)
            if before != after:
                found.append(f"cell {i}: widget model id or random animation id in an output")
                break
    return found


def _text(nb):
    return json.dumps(nb, indent=1, sort_keys=True, ensure_ascii=False) + "\n"


def strip_file(path):
    """Strip one notebook file in place; True when it changed."""
    path = Path(path)
    before = path.read_text(encoding="utf-8")
    nb = json.loads(before)
    after = _text(strip_notebook(nb))
    if after != before:
        path.write_text(after, encoding="utf-8")
        return True
    return False


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m ikteach.notebook_strip",
                                     description="Strip run noise from notebooks.")
    parser.add_argument("notebooks", nargs="+", help="notebook files")
    parser.add_argument("--check", action="store_true", help="only report, exit 1 on noise")
    args = parser.parse_args(argv)
    noisy = 0
    for path in args.notebooks:
        if args.check:
            found = noise(json.loads(Path(path).read_text(encoding="utf-8")))
            if found:
                noisy += 1
                print(f"{path}: " + "; ".join(found[:3]))
        elif strip_file(path):
            print(f"stripped {path}")
    return 1 if noisy else 0


if __name__ == "__main__":
    sys.exit(main())
