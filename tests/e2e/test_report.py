"""The main job's one-page report (python/report.py): the quick main job (python/run_main.py --quick) writes
OUTDIR/report.html and names it; the page holds summary.csv's figures with their units, the case line, the
banner that the quick run is not a result to report (with summary.csv's reason), and its pictures embedded.
Headless Chromium shows it: the screenshot (A4 at 150 dpi, 1240 x 1754) is not blank, the stress picture
is coloured where it lies on the page (the screenshot against one of the page without that picture), and
the page prints on one A4 sheet. The run's summary.csv made that of a converged, reportable run shows no
banner; a failed run's folder (no meshes, no figures) still gets its page, with the banner and the pictures
named missing; without matplotlib the page names the pictures it cannot draw. report.py's PLY reader reads the run's cage as the harness does, as ascii too, and binary faces of
mixed sizes. report.py --help prints the usage."""
import base64
import csv
import html
import os
import re
import shutil
import struct
import subprocess
import time

import numpy as np

import pipeline
import report
from harness import SOURCE, check, finish, workdir

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
WIDTH, HEIGHT = 1240, 1754  # A4 at 150 dpi


def text_of(page: str) -> str:
    """the page's visible text: tags (and the embedded pictures with them) dropped, entities resolved"""
    page = re.sub(r"<style>.*?</style>", " ", page, flags=re.S)
    return re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " ", page)))


def chromium(args: list, out: str) -> subprocess.CompletedProcess:
    """headless Chromium as root (no sandbox), its profile in the test's folder"""
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
           f"--user-data-dir={os.path.join(out, 'chromium-profile')}"] + args
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=180)


def screenshot(page: str, png: str, out: str) -> subprocess.CompletedProcess:
    return chromium([f"--screenshot={png}", f"--window-size={WIDTH},{HEIGHT}", "file://" + page], out)


def png_size(path: str):
    with open(path, "rb") as fh:
        head = fh.read(24)
    return struct.unpack(">II", head[16:24]) if head[:8] == b"\x89PNG\r\n\x1a\n" else None


def pixels(path: str):
    import matplotlib.image
    return matplotlib.image.imread(path)[:, :, :3]  # floats in [0, 1]


out = workdir("report")
h = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "report.py"), "--help"], cwd=out,
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
check(h.returncode == 0 and h.stdout.startswith("usage: report.py") and "OUTDIR" in h.stdout.upper(),
      "report.py --help prints the usage", h.stdout[-800:])

# the quick main job writes the report and names it
run = os.path.join(out, "main")
p = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "run_main.py"), run, "--quick"],
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1800)
print(p.stdout[-1500:])
check(p.returncode == 0, "main job --quick exits 0", p.stdout[-3000:])
page_path = os.path.join(run, "report.html")
check(p.stdout.rstrip().endswith(f"Report (one page, for the surgeon; open it in a browser): {page_path}"),
      "the main job ends naming its report")
check(os.path.exists(page_path), "report.html written")
if not os.path.exists(page_path):
    finish()
first = text_of(open(page_path, encoding="utf-8").read())
check(f"by python3 {os.path.join(SOURCE, 'python', 'run_main.py')} {run} --quick" in first
      and re.search(r"Report made on \d{4}-\d\d-\d\d \d\d:\d\d", first), "report.html: the main job's command and the date")
# report.py OUTDIR writes it again, on its own (and is timed: the pictures are drawn from the meshes)
t0 = time.time()
r = subprocess.run(["/usr/bin/python3", os.path.join(SOURCE, "python", "report.py"), run],
                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
seconds = time.time() - t0
check(r.returncode == 0 and r.stdout.strip() == page_path, f"report.py OUTDIR writes report.html ({seconds:.1f} s)", r.stdout)
check(seconds < 30, f"report.py takes under 30 s ({seconds:.1f} s)")
page = open(page_path, encoding="utf-8").read()
text = text_of(page)
check(f"report.py {run}" in text, "report.html written by report.py names report.py's command")
s = pipeline.read_summary(os.path.join(run, "summary.csv"))
SEX = {"M": "male", "F": "female"}


def signed(v: str) -> str:
    """a change as the page gives it: with its sign"""
    return v if v.startswith("-") else "+" + v


# the figures of summary.csv, each with its unit, and the case line
expected = {
    "force": f"{s['force_N']} N", "elevation": f"{s['elevation_mm']} mm", "max stress": f"{s['max_stress_MPa']} MPa",
    "max stress where": f"at the {s['max_stress_where']}",
    "max stress away from the junctions": f"{s['max_stress_body_MPa']} MPa",
    "max strain": f"{s['max_strain']} ({float(s['max_strain']) * 100:.1f} %)", "max strain where": f"at the {s['max_strain_where']}",
    "slice volume change": f"{signed(s['slice_change_cm3'])} cm³ ({signed(s['slice_change_pct'])} %)",
    "envelope volume change": f"{signed(s['envelope_change_cm3'])} cm³ ({signed(s['envelope_change_pct'])} %)",
    "pectus index before -> after": f"{s['haller_index_before']} → {s['haller_index_after']}",
    "case": f"Case {s['case']}", "sex and age": f"{SEX[s['sex']]}, {s['age_years']} years",
    "target elevation": f"target elevation of the lower end of the sternum {s['target_elevation_mm']} mm",
    "bar space": f"intercostal space (between ribs {s['bar_intercostal_space']} and {int(s['bar_intercostal_space']) + 1})",
    "settings": f"{s['fe_tets']} {s['fe_element']} tetrahedra",
    "material": f"bone E = {s['bone_E_MPa']} MPa",
}
missing = {k: v for k, v in expected.items() if v not in text}
check(all(s[k] for k in ("force_N", "max_stress_MPa", "max_strain", "slice_change_cm3", "haller_index_after")) and not missing,
      "report.html: summary.csv's figures with their units, the case line and the settings", str(missing))
check(text.index(f"{s['force_N']} N") < text.index(f"{s['haller_index_before']} →") < text.index("bone E ="),
      "report.html: the figures before the settings' small print")
# quick: the banner, with summary.csv's reason
reason = s["not_reportable_because"]
check(s["reportable"] == "0" and reason and "id='not-reportable'" in page and "NOT A RESULT TO REPORT" in text
      and f"Technical reason: {reason}" in text, "report.html: the quick run's banner says it is not a result to report, and why")
check(text.index("NOT A RESULT TO REPORT") < text.index(f"{s['force_N']} N"), "report.html: the banner above the figures")
# self-contained: every picture embedded (three PNGs), nothing fetched
srcs = re.findall(r"""src=['"]([^'"]*)['"]""", page)
pngs = [base64.b64decode(x.split(",", 1)[1]) for x in srcs if x.startswith("data:image/png;base64,")]
check(len(srcs) == 3 and len(pngs) == 3 and all(b[:8] == b"\x89PNG\r\n\x1a\n" for b in pngs)
      and not re.search(r"""(href|src)=['"](?!data:)""", page) and "Picture missing" not in text,
      "report.html: self-contained, its three pictures embedded", str([x[:40] for x in srcs]))
for ident in ("stress-picture", "sections-picture", "force-picture"):
    check(f"id='{ident}'" in page, f"report.html: {ident}")

# the PLY reader: the cage and its stress as the harness reads them
import harness  # noqa: E402
mine, theirs = report.read_ply(os.path.join(run, "nuss_result.ply")), harness.read_ply(os.path.join(run, "nuss_result.ply"))
check(np.allclose(mine["V"], theirs["V"]) and np.array_equal(report.triangles(mine["F"]), np.array(theirs["F"]))
      and np.allclose(mine["vertex"]["quality"], theirs["vertex"]["quality"]), "report.read_ply reads nuss_result.ply as the harness does")

ascii_path = os.path.join(out, "result_ascii.ply")
harness.write_ply(ascii_path, theirs["V"], theirs["F"], vprops={"quality": ("float", theirs["vertex"]["quality"])})
a = report.read_ply(ascii_path)
check(np.allclose(a["V"], mine["V"], atol=1e-4) and np.array_equal(report.triangles(a["F"]), report.triangles(mine["F"]))
      and np.allclose(a["vertex"]["quality"], mine["vertex"]["quality"], atol=1e-4), "report.read_ply reads the same cage as ascii PLY")
# a triangle and a quad (lists of two lengths), binary: split into three triangles
mixed = os.path.join(out, "mixed.ply")
with open(mixed, "wb") as fh:
    fh.write(b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
             b"element face 2\nproperty list uchar int vertex_indices\nproperty float quality\nend_header\n")
    fh.write(struct.pack("<15f", 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0))
    fh.write(struct.pack("<B3if", 3, 1, 4, 2, 7.0) + struct.pack("<B4if", 4, 0, 1, 2, 3, 8.0))
m = report.read_ply(mixed)
check(report.triangles(m["F"]).tolist() == [[1, 4, 2], [0, 1, 2], [0, 2, 3]] and m["face"]["quality"].tolist() == [7.0, 8.0]
      and m["V"].shape == (5, 3), "report.read_ply: binary faces of mixed sizes, split into triangles", str(m["F"]))

# Chromium: the screenshot
shot = os.path.join(out, "report.png")
if check(os.path.exists(CHROMIUM), f"chromium installed ({CHROMIUM}; scripts/setup.sh installs it)"):
    t0 = time.time()
    c = screenshot(page_path, shot, out)
    shot_seconds = time.time() - t0
    check(c.returncode == 0 and os.path.exists(shot), f"chromium --headless --screenshot exits 0 and writes the PNG ({shot_seconds:.1f} s)",
          c.stdout[-1500:])
if os.path.exists(shot):
    check(png_size(shot) == (WIDTH, HEIGHT), f"screenshot is {WIDTH} x {HEIGHT} ({png_size(shot)})")
    img = pixels(shot)
    ink = (img.min(axis=2) < 0.9).mean()
    check(0.08 < ink < 0.7, f"screenshot is not blank: {ink:.1%} of the pixels are not white")
    # rows with ink spread down the page: the page is laid out, not one line at the top
    rows = np.nonzero((img.min(axis=2) < 0.9).any(axis=1))[0]
    check(len(rows) and rows.max() > 0.55 * HEIGHT, f"screenshot: ink down to {rows.max() if len(rows) else 0} px of {HEIGHT}")
    # the stress picture: the screenshot against one of the same page without it; where they differ, it is coloured
    bare_path = os.path.join(run, "report_without_stress.html")
    # hidden, it keeps its place: the rest of the page stays where it was
    open(bare_path, "w", encoding="utf-8").write(page.replace("</style>", "#stress-picture { visibility: hidden; }</style>", 1))
    bare = os.path.join(out, "report_without_stress.png")
    screenshot(bare_path, bare, out)
    if check(os.path.exists(bare) and png_size(bare) == (WIDTH, HEIGHT), "screenshot of the page without the stress picture"):
        diff = np.abs(img - pixels(bare)).max(axis=2) > 0.1
        ys, xs = np.nonzero(diff)
        area = diff.mean()
        check(area > 0.02, f"the stress picture covers {area:.1%} of the page")
        if len(ys):
            drawn = img[diff]  # the picture's own pixels: the cage, the colour bar, the labels
            saturation = drawn.max(axis=1) - drawn.min(axis=1)
            coloured = saturation > 0.2
            hues = {"blue": (coloured & (drawn[:, 2] > drawn[:, 0] + 0.15)).mean(),
                    "warm (red to yellow)": (coloured & (drawn[:, 0] > drawn[:, 2] + 0.25)).mean()}
            check(coloured.mean() > 0.3 and all(v > 0.01 for v in hues.values()),
                  f"the stress picture is coloured: {coloured.mean():.1%} of its pixels, "
                  + ", ".join(f"{k} {v:.1%}" for k, v in hues.items()))
            check(xs.min() > 0.3 * WIDTH and ys.max() < 0.6 * HEIGHT,
                  f"the stress picture lies in the upper right of the page (x from {xs.min()}, y to {ys.max()})")
    # one printed A4 page
    pdf = os.path.join(out, "report.pdf")
    chromium(["--no-pdf-header-footer", f"--print-to-pdf={pdf}", "file://" + page_path], out)
    data = open(pdf, "rb").read() if os.path.exists(pdf) else b""
    pages = len(re.findall(rb"/Type\s*/Page(?![s\w])", data))
    check(pages == 1, f"report.html prints on one page ({pages})")
    box = re.search(rb"/MediaBox\s*\[\s*0 0 ([0-9.]+) ([0-9.]+)\s*\]", data)
    check(box is not None and abs(float(box.group(1)) - 595.3) < 2 and abs(float(box.group(2)) - 841.9) < 2,
          f"the printed page is A4 ({box and box.groups()})")

# without matplotlib and numpy (imports that fail): the page still comes, with every figure, the two drawn pictures
# named missing and the FE filter's own force plot embedded
bare = subprocess.run(["/usr/bin/python3", "-c", "import sys; sys.modules.update(matplotlib=None, numpy=None); "
                       "sys.path.insert(0, sys.argv[1]); import report; sys.exit(report.main([sys.argv[2]]))",
                       os.path.join(SOURCE, "python"), run], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
t = text_of(open(page_path, encoding="utf-8").read()) if bare.returncode == 0 else ""
check(bare.returncode == 0 and t.count("Picture missing") == 2 and "drawing it needs matplotlib and numpy" in t
      and open(page_path).read().count("data:image/png;base64,") == 1 and f"{s['force_N']} N" in t and "NOT A RESULT TO REPORT" in t,
      "without matplotlib: the page with its figures, the stress and section pictures named missing, the FE's force plot",
      bare.stdout[-2000:])

# the run's summary.csv as that of a converged, reportable run (without the meshes: the banner is what counts): no banner
good = os.path.join(out, "reportable")
os.makedirs(good)
row = dict(s, reportable="1", not_reportable_because="", run_mode="full", fe_converged="1")
with open(os.path.join(good, "summary.csv"), "w", newline="") as fh:
    csv.writer(fh).writerows([list(row), list(row.values())])
report.write_report(good, "test")
t = text_of(open(os.path.join(good, "report.html"), encoding="utf-8").read())
check("NOT A RESULT TO REPORT" not in t and f"{s['force_N']} N" in t, "a reportable run's page has no banner")

# a failed run: no meshes, no figures; the page says so
failed = os.path.join(out, "failed")
os.makedirs(failed)
row = {k: ("" if k not in ("case", "sex", "age_years", "target_elevation_mm", "run_mode", "bar_intercostal_space") else v)
       for k, v in s.items()}
row.update(reportable="0", fe_converged="0", run_mode="full")
with open(os.path.join(failed, "summary.csv"), "w", newline="") as fh:
    csv.writer(fh).writerows([list(row), list(row.values())])
report.write_report(failed, "test")
t = text_of(open(os.path.join(failed, "report.html"), encoding="utf-8").read())
check("NOT A RESULT TO REPORT" in t and "gave no valid result" in t and t.count("Picture missing") == 3
      and "n/a" in t and f"Case {s['case']}" in t, "a failed run's page: the banner, n/a figures, the three pictures missing")
finish()
