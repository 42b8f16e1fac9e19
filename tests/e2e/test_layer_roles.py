"""The main job's script (python/pipeline.py, quick FE settings, an 8 mm cage) in a project that already holds other
layers: its layer parameters name layers by number (a position in 2020.09, an id in 2021.05 and later), which then
point at the wrong layers. The FE, volume and index filters take the layers by role instead (the cage's landmark
layer, the cage the FE result came from), say so in the Log, and give the same figures as the run in an empty
project. A layer parameter that no layer can fill is refused with the layers named, and nothing changes."""
import os

import pectus_mlx as mlx
import pipeline
from harness import check, check_refused, finish, run, workdir, write_ply

out = workdir("layer-roles")
script = pipeline.build_script(out, age=8, haller=5.3, elevation=44.7, quick=True)
for f in script.filters:  # the tests' coarse cage (8 mm edges), one MGA sweep: seconds, not minutes
    if f.name == pipeline.RIBCAGE:
        f.set(edgeLength=8.0)
    if f.name == pipeline.MGA:
        f.set(maxSweeps=1)
path = script.write(os.path.join(out, "pipeline.mlx"))

# unrelated layers loaded first: a closed box and a point cloud (no landmark codes)
box = os.path.join(out, "box.ply")
V = [[x, y, z] for x in (0, 10) for y in (0, 10) for z in (0, 10)]
F = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4],
     [1, 5, 7], [1, 7, 3]]
write_ply(box, V, F)
cloud = os.path.join(out, "cloud.ply")
write_ply(cloud, [[i, 2.0 * i, 0.5] for i in range(7)], [])

FIGURES = {pipeline.FE: ("force_N", "elevation_mm", "max_stress_MPa", "max_strain", "tets"),
           pipeline.MEASURES["slice"]: ("before_volume_cm3", "volume_cm3", "volume_change_cm3"),
           pipeline.MEASURES["envelope"]: ("before_volume_cm3", "volume_cm3", "volume_change_cm3"),
           pipeline.MEASURES["index"]: ("before_haller_index", "haller_index")}


def figures(r) -> dict:
    return {(f, k): r.get(k, f) for f, keys in FIGURES.items() for k in keys}


plain = run([], path)
check(plain.rc == 0, "the script runs in an empty project", "\n".join(plain.log[-20:]))
ref = figures(plain)
check(all(v is not None for v in ref.values()), "every figure is there", str(ref))
check(not any(l.startswith(("landmark layer:", "before layer:")) for l in plain.log),
      "in an empty project the named layers are the ones taken (no note in the Log)")

for inputs, what in (([box], "a mesh"), ([box, cloud], "a mesh and a point cloud")):
    r = run(inputs, path)
    check(r.rc == 0, f"after {what} loaded first: the script runs", "\n".join(r.log[-20:]))
    got = figures(r)
    diff = {k: (ref[k], got[k]) for k in ref if got[k] != ref[k]}
    check(not diff, f"after {what} loaded first: the same figures as in an empty project", str(diff))
    notes = [l for l in r.log if l.startswith(("landmark layer:", "before layer:"))]
    print("\n".join(notes))
    check(any(l.startswith("landmark layer: 'ribcage landmarks'") and "not a landmark layer" in l for l in notes)
          and any(l.startswith("before layer: 'pectus rib cage'") for l in notes),
          f"after {what} loaded first: the Log names the layers taken instead and why", "\n".join(notes))

# nothing fills the role: a clear refusal naming the layers, exit non-zero (meshlabserver saves nothing after it)
index = pipeline.measure_filter("index", 0, 1)
lonely = mlx.Script([mlx.Filter("Pectus: Create Rib Cage", **dict(script.filters[0].params)), index])
r = run([box], lonely)
check_refused(r, "no before layer for layer", "Pectus Index with compare and no before state")
check_refused(r, "turn 'Compare' off", "the refusal says what to do")
finish()
