"""Every filter has a page in docs/filters whose parameter table lists exactly the parameters the plugin
declares (the plugins loaded in-process by pectus_layer_check --params), in the declared order, with the
same type and default, and every numeric parameter with the range the plugin declares; the README links every page; no relative link of the README or docs/ is broken.
Every filter python/pectus_filters.py defines has the plugin's parameters, in order, with the same types,
defaults and enum labels.
Every parameter's tool-tip (the filter's help text, with " Range: [lo, hi]." for numeric parameters) is at most
TOOLTIP_MAX characters: MeshLab 2020.09's dialog shows it in two lines of about 50 characters and cuts the rest."""
from __future__ import annotations

import os
import re
import subprocess
import xml.etree.ElementTree as ET

import glob
import inspect
import sys

from docs_pages import FILTER_PAGES, PARAM_COLUMNS, SOURCE, broken_links, parameter_table, read
from harness import check, finish

BUILD = os.environ.get("PECTUS_BUILD", os.path.join(SOURCE, "build"))
PLUGINS = os.environ.get("PECTUS_PLUGINS", os.path.join(BUILD, "plugins"))
# MeshLab 2020.09's filter dialog ("Help"): each tool-tip is word-wrapped to about 50 characters in a row two
# lines tall; longer text is cut. The details belong in the parameter tables of docs/filters.
TOOLTIP_MAX = 100
# The FE analysis and the bar planner fill the screen's height, so a help row cannot grow: two lines of about
# 45 characters, which word-wrapping fills to about 80 (seen in the dialog with its help shown)
TOOLTIP_MAX_FULL_DIALOG = {"Pectus: Nuss Procedure FE Analysis": 80, "Pectus: Nuss Bar Planner": 80}


def declared() -> tuple[dict, dict, dict]:
    """filter name -> [(name, type, default text, enum labels)] as the plugins declare them,
    filter name -> {parameter name -> (lo, hi, lo open, hi open)} for the numeric parameters, and
    filter name -> {parameter name -> tool-tip as the dialog shows it}"""
    out = subprocess.run(["xvfb-run", "-a", os.path.join(BUILD, "bin", "pectus_layer_check"), "--params", PLUGINS],
                         capture_output=True, text=True, timeout=300)
    if out.returncode != 0:
        raise SystemExit(f"pectus_layer_check --params failed ({out.returncode}): {out.stderr}")
    filters, ranges, tooltips = {}, {}, {}
    for f in ET.fromstring(out.stdout).iter("filter"):
        check_dialog_info(f.attrib["name"], f.attrib["info"])
        params = []
        tooltips[f.attrib["name"]] = {p.attrib["name"]: p.attrib.get("tooltip", "") for p in f.iter("Param")}
        ranges[f.attrib["name"]] = {
            p.attrib["name"]: (float(p.attrib["min"]), float(p.attrib["max"]), p.attrib["minOpen"] == "true",
                               p.attrib["maxOpen"] == "true")
            for p in f.iter("Param") if "min" in p.attrib}
        for p in f.iter("Param"):
            a = p.attrib
            kind = a["type"][len("Rich"):] if a["type"].startswith("Rich") else a["type"]
            labels = [a[f"enum_val{i}"] for i in range(int(a.get("enum_cardinality", 0)))]
            if kind == "Point3f":
                value = f"{a['x']}, {a['y']}, {a['z']}"
            else:
                value = a.get("value", "")
            params.append((a["name"], kind, value, labels))
        filters[f.attrib["name"]] = params
    return filters, ranges, tooltips


def check_tooltips(tooltips: dict):
    """every tool-tip fits the dialog of MeshLab 2020.09 (TOOLTIP_MAX characters)"""
    count = sum(len(tips) for tips in tooltips.values())
    check(count >= 50, f"the plugins declare {count} parameters with tool-tips")
    for fname, tips in tooltips.items():
        most = TOOLTIP_MAX_FULL_DIALOG.get(fname, TOOLTIP_MAX)
        for name, tip in tips.items():
            check(len(tip) <= most, f"{fname}: the tool-tip of {name} is at most {most} characters",
                  f"it has {len(tip)}: {tip!r}")


INFO_CHARACTERS = 150  # three lines of the narrowest dialog (about 50 characters a line)


def check_dialog_info(name: str, info: str):
    """the dialog's description: at most three lines, then a link to the filter's page in the installed docs"""
    text, _, link = info.partition("<br>Details: ")
    shown = re.sub(r"&\w+;", "x", re.sub(r"<[^>]+>", "", text))
    check(len(shown) <= INFO_CHARACTERS, f"{name}: dialog description within {INFO_CHARACTERS} characters",
          f"{len(shown)}: {shown}")
    page = re.search(r'href="file://[^"]*/filters/([\w.]+\.md)"', link)
    check(page is not None and os.path.isfile(os.path.join(SOURCE, "docs", "filters", page.group(1))),
          f"{name}: the dialog links its docs page", link)


# a number as the docs write it: 100,000 (thousands), 0.05, 1e6, -1e6, –0.4 (an en dash as minus)
NUMBER = r"[-–−]?(?:\d{1,3}(?:,\d{3})+|\d+(?:\.\d+)?)(?:e[+-]?\d+)?"
BRACKETS = re.compile(r"([\[(])\s*(" + NUMBER + r")\s*,\s*(" + NUMBER + r")\s*([\])])")
DASH = re.compile(r"(" + NUMBER + r")\s+[–-]\s+(" + NUMBER + r")")


def number(text: str) -> float:
    return float(text.replace(",", "").replace("–", "-").replace("−", "-"))


def doc_range(cell: str):
    """(lo, hi, lo open, hi open) of the first range a docs table cell gives: an interval "[0, 1)",
    "(0, 1e6]", or "lo – hi" (both ends included); None if it gives none"""
    cell = cell.replace("`", "")
    found = [m for m in (BRACKETS.search(cell), DASH.search(cell)) if m]
    if not found:
        return None
    m = min(found, key=lambda m: m.start())
    if m.re is BRACKETS:
        return number(m.group(2)), number(m.group(3)), m.group(1) == "(", m.group(4) == ")"
    return number(m.group(1)), number(m.group(2)), False, False


def range_text(r) -> str:
    lo, hi, lo_open, hi_open = r
    return f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"


def same_range(doc, code) -> bool:
    return doc is not None and same_number(str(doc[0]), str(code[0])) and same_number(str(doc[1]), str(code[1])) \
        and doc[2:] == code[2:]


def same_number(doc: str, code: str) -> bool:
    try:
        d, c = float(doc), float(code)
    except ValueError:
        return False
    return abs(d - c) <= 1e-6 * max(1.0, abs(c))


def default_matches(kind: str, doc: str, code: str, labels: list) -> bool:
    doc = doc.strip()
    if "(computed)" in doc or kind == "Mesh":
        return True
    if kind in ("Float", "Int"):
        return same_number(doc.strip("`"), code)
    if kind == "Bool":
        return doc.strip("`").lower() == code.lower()
    if kind == "Enum":
        return 0 <= int(code) < len(labels) and doc.strip("`") == labels[int(code)]
    if kind == "Point3f":
        d = [x.strip() for x in doc.strip("`").split(",")]
        c = [x.strip() for x in code.split(",")]
        return len(d) == 3 and all(same_number(a, b) for a, b in zip(d, c))
    # String, SaveFile
    return (doc == "(empty)" and code == "") or doc.strip("`") == code


def check_python_filters(filters: dict):
    """python/pectus_filters.py: each filter function's defaults are the plugin's declaration"""
    sys.path.insert(0, os.path.join(SOURCE, "python"))
    import pectus_filters
    functions = [f for n, f in inspect.getmembers(pectus_filters, inspect.isfunction)
                 if not n.startswith("_") and f.__module__ == pectus_filters.__name__]
    check(len(functions) >= 5, f"python/pectus_filters.py defines {len(functions)} filters")
    for fn in functions:
        f = fn()
        where = f"python/pectus_filters.py {fn.__name__}()"
        if not check(f.name in filters, f"{where}: '{f.name}' is a filter's name"):
            continue
        plugin = filters[f.name]
        check(list(f.params) == [p[0] for p in plugin], f"{where}: the parameters as declared, in order",
              f"\n  python: {list(f.params)}\n  plugin: {[p[0] for p in plugin]}")
        for name, kind, value, labels in plugin:
            if name not in f.params:
                continue
            a = ET.fromstring(f.params[name].xml(name)).attrib
            mine = a["type"][len("Rich"):]
            check(mine == kind, f"{where}: {name} is {kind}", f"python says {mine}")
            if kind == "Enum":
                mine_labels = [a[f"enum_val{i}"] for i in range(int(a.get("enum_cardinality", 0)))]
                check(mine_labels == labels and a["value"] == value, f"{where}: {name}'s labels and default as declared",
                      f"python: {a['value']} of {mine_labels}; plugin: {value} of {labels}")
            elif kind in ("Float", "DynamicFloat", "Int", "Point3f"):
                mine_value = f"{a['x']}, {a['y']}, {a['z']}" if kind == "Point3f" else a["value"]
                check(all(same_number(m, v) for m, v in zip(mine_value.split(","), value.split(","))),
                      f"{where}: {name} defaults to {value}", f"python says {mine_value}")
            elif kind != "Mesh":
                check(a.get("value", "").lower() == value.lower(), f"{where}: {name} defaults to {value!r}",
                      f"python says {a.get('value')!r}")


def main():
    filters, ranges, tooltips = declared()
    check_tooltips(tooltips)
    check_python_filters(filters)
    check(len(filters) >= 14, f"the plugins declare {len(filters)} filters")
    pages = {}
    for path in FILTER_PAGES:
        title, header, rows = parameter_table(path)
        name = os.path.relpath(path, SOURCE)
        check(title in filters, f"{name}: its title '{title}' is a filter's name")
        check(header == PARAM_COLUMNS, f"{name}: a '## Parameters' table with columns {PARAM_COLUMNS}", str(header))
        pages[title] = (name, rows)
    for fname, params in filters.items():
        if not check(fname in pages, f"'{fname}' has a page in docs/filters"):
            continue
        page, rows = pages[fname]
        doc_names = [r[0].strip("`") for r in rows]
        code_names = [p[0] for p in params]
        check(doc_names == code_names, f"{page}: the parameters as declared, in order",
              f"\n  page:   {doc_names}\n  plugin: {code_names}")
        by_name = {r[0].strip("`"): r for r in rows}
        for name, kind, value, labels in params:
            kind = "Float" if kind == "DynamicFloat" else kind  # a bounded float is a float to the reader
            r = by_name.get(name)
            if r is None or len(r) != len(PARAM_COLUMNS):
                continue
            check(r[1] == kind, f"{page}: {name} is {kind}", f"page says {r[1]!r}")
            shown = labels[int(value)] if kind == "Enum" and value.isdigit() and int(value) < len(labels) else value
            check(default_matches(kind, r[2], value, labels), f"{page}: {name} defaults to {shown}",
                  f"page says {r[2]!r}")
            check(r[4] != "", f"{page}: {name} is described")
            if kind in ("Float", "Int"):
                code = ranges[fname].get(name)
                if check(code is not None, f"{fname}: {name} is declared with its range"):
                    check(same_range(doc_range(r[3]), code), f"{page}: {name}'s range is {range_text(code)}",
                          f"page says {r[3]!r}")
    readme = read(os.path.join(SOURCE, "README.md"))
    for path in FILTER_PAGES:
        rel = os.path.relpath(path, SOURCE)
        check(re.search(r"\]\(" + re.escape(rel) + r"\)", readme) is not None, f"README links {rel}")
    docs = [os.path.join(SOURCE, "README.md")] + glob.glob(os.path.join(SOURCE, "docs", "**", "*.md"), recursive=True)
    for path in sorted(docs):
        bad = broken_links(path)
        check(not bad, f"{os.path.relpath(path, SOURCE)}: every relative link resolves", str(bad))
    finish()


if __name__ == "__main__":
    main()
