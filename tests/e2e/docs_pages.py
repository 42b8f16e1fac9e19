"""Reading the user documentation as the docs tests check it: the filter pages' parameter tables
(docs/filters/*.md) and the shell blocks of the README and of docs/."""
from __future__ import annotations

import glob
import os
import re

SOURCE = os.environ.get("PECTUS_SOURCE", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
FILTER_PAGES = sorted(glob.glob(os.path.join(SOURCE, "docs", "filters", "*.md")))
PARAM_COLUMNS = ["parameter", "type", "default", "range", "description"]


def read(path: str) -> str:
    with open(path, encoding="utf-8") as fh:
        return fh.read()


def page_title(text: str) -> str:
    first = text.splitlines()[0] if text else ""
    return first[2:].strip() if first.startswith("# ") else ""


def table_rows(text: str, heading: str) -> tuple[list[str], list[list[str]]]:
    """(header cells, rows of cells) of the first table after the line `heading`"""
    lines = text.splitlines()
    if heading not in lines:
        return [], []
    table = []
    for line in lines[lines.index(heading) + 1:]:
        if line.startswith("|"):
            table.append([c.strip() for c in line.strip().strip("|").split("|")])
        elif table or line.startswith("#"):
            break
    if len(table) < 2:
        return [], []
    return table[0], [r for r in table[2:]]


def parameter_table(path: str) -> tuple[str, list[str], list[list[str]]]:
    text = read(path)
    header, rows = table_rows(text, "## Parameters")
    return page_title(text), header, rows


def shell_blocks(path: str) -> list[tuple[int, str, str]]:
    """(line, info string, body) of every fenced block whose info string starts with `sh`"""
    out, lines, i = [], read(path).splitlines(), 0
    while i < len(lines):
        m = re.match(r"^\s*```(sh(?:\s+\w+)*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        start, body = i + 1, []
        i += 1
        while i < len(lines) and not lines[i].strip().startswith("```"):
            body.append(lines[i])
            i += 1
        out.append((start, m.group(1), "\n".join(body) + "\n"))
        i += 1
    return out


def anchor(heading: str) -> str:
    """GitHub's anchor of a Markdown heading"""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower().replace("`", ""))
    return text.replace(" ", "-")


def broken_links(path: str) -> list[str]:
    """relative links of a Markdown file whose file or #anchor does not exist"""
    out, base = [], os.path.dirname(path)
    text = re.sub(r"```.*?```", "", read(path), flags=re.S)
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"^[a-z]+:", target):
            continue
        file, _, frag = target.partition("#")
        dest = os.path.normpath(os.path.join(base, file)) if file else path
        if not os.path.exists(dest):
            out.append(target)
        elif frag and dest.endswith(".md"):
            heads = [anchor(l.lstrip("#")) for l in read(dest).splitlines() if l.startswith("#")]
            if frag not in heads:
                out.append(target)
    return out
