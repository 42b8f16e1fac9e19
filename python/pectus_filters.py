"""Complete, typed filter definitions of the pectus-meshlab filters for .mlx scripts (standard library only).

Each function returns a pectus_mlx.Filter with every parameter the filter declares (meshlabserver aborts
on a missing one), defaults as in the GUI, any of them overridable by keyword:

    from pectus_filters import create_ribcage, nuss_fea
    s = Script([create_ribcage(edgeLength=4.0, hallerIndex=5.3, age=8), nuss_fea(landmarkLayer=1)])
"""
from __future__ import annotations

import pectus_mlx as mlx
from pectus_mlx import Bool, DynamicFloat, Enum, Filter, Float, Int, Mesh, SaveFile, String


def _build(name: str, spec: dict, overrides: dict) -> Filter:
    params = {}
    for key, (kind, default, *extra) in spec.items():
        v = overrides.pop(key, default)
        if isinstance(v, mlx._P):
            params[key] = v
        elif kind is Enum:
            params[key] = Enum(v, extra[0])
        elif kind is DynamicFloat:
            params[key] = DynamicFloat(v, *extra[0])
        else:
            params[key] = kind(v)
    if overrides:
        raise TypeError(f"{name}: unknown parameter(s) {sorted(overrides)}")
    return Filter(name, **params)


RIBCAGE_SIZE = ["From age", "Explicit dimensions"]
RIBCAGE_CARTILAGE = ["The rib's", "Circular, twice the rib's area (CT)"]
RIBCAGE_OUTPUT = ["One labelled surface", "One layer per tissue (as CT segmentation)"]


def create_ribcage(**kw) -> Filter:
    return _build("Pectus: Create Rib Cage", {
        "sizeMode": (Enum, 0, RIBCAGE_SIZE), "age": (Float, 7.0), "chestWidth": (Float, 181.0),
        "chestDepth": (Float, 74.0), "spineHeight": (Float, 172.0), "ribPairs": (Int, 12),
        "hallerIndex": (Float, 4.0), "funnelCenterX": (Float, 0.0), "funnelCenterZ": (Float, 1.1),
        "funnelWidth": (Float, 80.0), "funnelHeight": (Float, 70.0), "edgeLength": (Float, 2.0),
        "cartilageSection": (Enum, 0, RIBCAGE_CARTILAGE), "output": (Enum, 0, RIBCAGE_OUTPUT)}, dict(kw))


def import_ct_segmentation(**kw) -> Filter:
    return _build("Pectus: Import CT Segmentation", {
        "path": (String, ""), "labelTable": (String, ""), "minVoxels": (Int, 1)}, dict(kw))


PREPARE_UNITS = ["Automatic", "Millimetres", "Centimetres", "Metres"]
PREPARE_FRAME = ["Automatic (from the anatomy)", "RAS (x right, y anterior, z superior)",
                 "LPS (x left, y posterior, z superior)", "Project frame (x left, y anterior, z superior)"]
PREPARE_SPINE = ["cut at the costovertebral joints", "keep as the fixed support"]


def prepare_patient_rib_cage(**kw) -> Filter:
    return _build("Pectus: Prepare Patient Rib Cage", {
        "units": (Enum, 0, PREPARE_UNITS), "frame": (Enum, 0, PREPARE_FRAME), "minVolume": (Float, 200.0),
        "gridStep": (Float, 0.8), "edgeLength": (Float, 4.0),
        "spine": (Enum, 0, PREPARE_SPINE), "pickedPoints": (String, "")}, dict(kw))


NUSS_INPUT = ["Current layer (one labelled surface)", "One layer per tissue (visible layers)"]
NUSS_MODE = ["Calibrate Fe to the target elevation", "Given elevating force"]
NUSS_ANALYSIS = ["Large displacement (nonlinear)", "Small strain (linear)"]
NUSS_ORDER = ["Quadratic TET10 (no locking)", "Linear TET4 (thesis, ANSYS SOLID185)"]
NUSS_MATERIAL = ["St Venant-Kirchhoff", "Neo-Hookean (FEBio)", "Neo-Hookean (CalculiX hyperelastic)"]
NUSS_NEWTON = ["Line search and adaptive steps", "Plain Newton, fixed steps"]
NUSS_CALIBRATION_METHOD = ["Force search", "Displacement control"]
NUSS_FIELD = ["von Mises stress (MPa)", "Equivalent strain"]
SIDES = ["Right", "Left"]


MODULUS_RANGE = (0.0, 1e6)  # the declared range of the moduli and the maximum force (the bounded float's slider)

# parameter groups the FE filter and the bar planner share (as in filter_nuss_fea.cpp)
NUSS_CALIBRATION = {"targetElevation": (Float, 0.0), "maxForce": (DynamicFloat, 1000.0, MODULUS_RANGE), "tolerance": (Float, 0.1),
                    "calibration": (Enum, 1, NUSS_CALIBRATION_METHOD)}
NUSS_MODEL = {"analysis": (Enum, 0, NUSS_ANALYSIS), "material": (Enum, 1, NUSS_MATERIAL), "newton": (Enum, 0, NUSS_NEWTON),
              "order": (Enum, 0, NUSS_ORDER), "tetQuality": (Float, 2.0),
              "maxTetVolume": (Float, 0.0), "boneModulus": (DynamicFloat, 11500.0, MODULUS_RANGE),
              "cartilageModulus": (DynamicFloat, 12.25, MODULUS_RANGE),
              "nuBone": (Float, 0.3), "nuCartilage": (Float, 0.4)}
NUSS_PATCHES = {"jointRadius": (Float, 6.0), "sternumLoadRadius": (Float, 8.0), "ribSupportRadius": (Float, 6.0)}


def nuss_fea(**kw) -> Filter:
    return _build("Pectus: Nuss Procedure FE Analysis", {
        "input": (Enum, 0, NUSS_INPUT), "landmarkLayer": (Mesh, 1), "intercostalSpace": (Int, 4),
        "mode": (Enum, 0, NUSS_MODE), "force": (Float, 140.0), **NUSS_CALIBRATION, **NUSS_MODEL, **NUSS_PATCHES,
        "field": (Enum, 0, NUSS_FIELD),
        "pathSide": (Enum, 0, SIDES), "pathRib": (Int, 5), "resultBase": (SaveFile, "")}, dict(kw))


PLANNER_BARS = ["One and two bars", "One bar", "Two bars"]
PLANNER_BEST = ["Lowest force", "Lowest max stress"]


def nuss_bar_planner(**kw) -> Filter:
    return _build("Pectus: Nuss Bar Planner", {
        "landmarkLayer": (Mesh, 1), "levels": (String, "3,4,5"), "bars": (Enum, 0, PLANNER_BARS),
        "secondOffset": (Int, -1), "secondShare": (Float, 0.5), **NUSS_CALIBRATION, **NUSS_MODEL, **NUSS_PATCHES,
        "best": (Enum, 0, PLANNER_BEST), "csvFile": (SaveFile, "")}, dict(kw))
