"""E2E: the private MeshLab prefix can be remade while MeshLab starts from it (a `cmake --build build` during a
test run remakes build/prefix): scripts/make_prefix.sh runs again and again into a copy of the prefix while
meshlabserver starts from that copy, and every start finds every plugin, as many filters and io plugins as a
start before."""
import os
import re
import shutil
import subprocess
import threading

import harness as h
from harness import check

W = h.workdir("prefix")
PREFIX = os.path.join(W, "prefix")
PLUGINS = os.environ.get("PECTUS_PLUGINS", os.path.join(os.path.dirname(h.PREFIX), "plugins"))
OURS = sorted(re.sub(r"^lib|\.so$", "", f) for f in os.listdir(PLUGINS) if f.endswith(".so"))
MAKE = [os.path.join(h.SOURCE, "scripts", "make_prefix.sh"), PREFIX, PLUGINS, *OURS]
EMPTY = os.path.join(W, "empty.mlx")
with open(EMPTY, "w") as fh:
    fh.write("<!DOCTYPE FilterScript>\n<FilterScript>\n</FilterScript>\n")


def start():
    """(filtering actions, io plugins) that meshlabserver from the copy reports at start"""
    p = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", os.path.join(PREFIX, "bin", "meshlabserver"),
                        "-s", EMPTY], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    f = re.search(r"Total (\d+) filtering actions", p.stdout)
    io = re.search(r"Total (\d+) io plugins", p.stdout)
    return (int(f.group(1)) if f else 0, int(io.group(1)) if io else 0)


subprocess.run(MAKE, check=True)
# a link to a plugin that is gone: removed by the next run
os.symlink("/nonexistent/libgone.so", os.path.join(PREFIX, "lib", "x86_64-linux-gnu", "meshlab", "plugins", "libgone.so"))
subprocess.run(MAKE, check=True)
check(not os.path.lexists(os.path.join(PREFIX, "lib", "x86_64-linux-gnu", "meshlab", "plugins", "libgone.so")),
      "a link to a plugin that is no longer there is removed")
ref = start()
check(ref[0] > 100 and ref[1] > 5, f"meshlabserver from the copy: {ref[0]} filtering actions, {ref[1]} io plugins")

stop = threading.Event()
remade = [0]


def remake():
    while not stop.is_set():
        subprocess.run(MAKE, check=True)
        remade[0] += 1


t = threading.Thread(target=remake)
t.start()
try:
    seen = [start() for _ in range(12)]
finally:
    stop.set()
    t.join()
check(remade[0] >= 3, f"the prefix was remade {remade[0]} times during the starts")
bad = [s for s in seen if s != ref]
check(not bad, f"every one of {len(seen)} starts during the remakes found {ref[0]} filtering actions and {ref[1]} io plugins",
      f"{bad}")
shutil.rmtree(W, ignore_errors=True)
h.finish()
