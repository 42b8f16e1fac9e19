"""E2E: TotalSegmentator's own output on a real CT (tests/data/totalsegmentator, Apache-2.0: a partial scan of the
lower chest, ribs 7-12, no sternum), through 'Pectus: Import CT Segmentation' and 'Pectus: Prepare Patient Rib Cage'. Checks:
  - the label map: every label it holds is a layer named from its label table (39 labels), the rib cage's
    structures among them recognised and every organ left out by its name (none is a candidate sternum);
  - the label map and the folder of masks: refused, the message naming what is missing (the sternum), the
    ribs the scan holds and the z range it spans, and saying the scan is partial; no layer is added."""
import gzip
import os
import re
import struct

import numpy as np

import harness as h
import pectus_mlx as mlx
from harness import check, check_refused
from pectus_filters import import_ct_segmentation, prepare_patient_rib_cage

DATA = os.path.join(h.SOURCE, "tests", "data", "totalsegmentator")


def labels_in(path):
    """the non-zero labels of a NIfTI-1 label map (integer data), read with numpy"""
    raw = gzip.open(path).read()
    dims = struct.unpack("<8h", raw[40:48 + 8])[1:4]
    dtype = {2: "u1", 4: "<i2", 8: "<i4", 512: "<u2", 768: "<u4"}[struct.unpack("<h", raw[70:72])[0]]
    offset = int(struct.unpack("<f", raw[108:112])[0])
    data = np.frombuffer(raw[offset:offset + int(np.prod(dims)) * np.dtype(dtype).itemsize], dtype=dtype)
    return int(np.count_nonzero(np.unique(data)))


def prepare(path):
    return h.run([], mlx.Script([import_ct_segmentation(path=path), prepare_patient_rib_cage()]))


# --- the label map with its organs ----------------------------------------------------------------------------
r = prepare(os.path.join(DATA, "labelmap.nii.gz"))
imported = r.get("structures", "Pectus: Import CT Segmentation")
check(imported == labels_in(os.path.join(DATA, "labelmap.nii.gz")),
      f"label map: one layer per label it holds ({imported})", "\n".join(r.log[:5]))
organs = [l for l in r.log if "': not part of the rib cage, left out" in l]
check(any("'colon'" in l for l in organs) and any("'pancreas'" in l for l in organs) and len(organs) >= 20,
      f"label map: the organs left out by their name ({len(organs)} layers)", "\n".join(r.log[:60]))
check(not any("equally good sternums" in l or "by their shape" in l for l in r.log),
      "label map: no organ is classified by its shape", "\n".join(l for l in r.log if "shape" in l))
check_refused(r, "No sternum", "label map")
msg = next((l for l in r.log if "No sternum" in l), "")
span = re.search(r"The layers span z = (\S+) to (\S+) \(file units\)", msg)
check(span is not None and "left ribs 7-12" in msg and "right ribs 7-12" in msg and "scan looks partial" in msg,
      "label map: the refusal names the ribs the scan holds, the z range it spans, and that it is partial", msg)
if span:
    z0, z1 = float(span.group(1)), float(span.group(2))
    check(60 < z1 - z0 < 100, f"label map: the span is the scan's: 30 slices of 3 mm hold {z1 - z0:.1f} mm of ribs")

# --- one mask per structure --------------------------------------------------------------------------------------
r = prepare(os.path.join(DATA, "masks"))
check_refused(r, "No sternum", "masks")
msg = next((l for l in r.log if "No sternum" in l), "")
check("left ribs 7-12" in msg and "'vertebrae_T11'" in msg and "scan looks partial" in msg,
      "masks: the refusal names what the scan holds and that it is partial", msg)

h.finish()
