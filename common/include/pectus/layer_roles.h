// The roles a filter's layer parameters ask for, checked on the layers' contents rather than on their
// positions: a landmark layer (points whose vertex quality holds landmark codes, labels.h) that lies on the
// cage it belongs to, and a before layer (the same mesh as the measured one: its undeformed state).
// A script names layers by position (MeshLab 2020.09) or by id (2021.05 and later); in a project that held
// other layers first, those numbers name other layers. The adapters take the named layer when it has the
// role, else the one layer of the document that has it, and refuse with the candidates named when none or
// several have it.
#pragma once
#include <string>
#include <vector>

#include "pectus/cmesh.h"

namespace pectus {

/// One layer of the document, as the role checks see it.
struct LayerRef {
  std::string label;
  const CMeshO* mesh = nullptr;
  /// the number a script gives this layer (2020.09: its position; 2021.05 and later: its id)
  int number = 0;
};

/// What the choice found: `index` into the layers; `note` says why that is not the named layer (empty when it is).
struct LayerChoice {
  int index = -1;
  std::string note;
};

/// A code of labels.h: costovertebral joints 100*side + rib, 500-503, bar exits 600 + 10*side + s, 700, 701.
bool isLandmarkCode(int code);

/// Why `m` is not a landmark layer holding the codes `needed` (a point layer whose every vertex quality is an
/// integer code, at least one of them a landmark code of labels.h), as a clause for messages ("which is not a
/// landmark layer (it has 9058 faces; ...)"); empty when it is one.
std::string landmarkLayerProblem(const CMeshO& m, const std::vector<int>& needed);

/// How far the landmark layer lies from the surfaces it belongs to (mm): the largest distance from a
/// costovertebral joint landmark or the lower sternum end (500) or the funnel's deepest point (501) to the
/// nearest vertex of any of `surfaces`. A landmark layer of another cage, or one moved with a deformed copy,
/// lies tens of millimetres away at the sternum. Infinity when the layer has none of those codes.
double landmarkDistance(const CMeshO& landmarks, const std::vector<const CMeshO*>& surfaces);

/// The distance up to which a landmark layer lies on `surfaces` (mm): 3 mean edge lengths, at least 10 mm.
double landmarkTolerance(const std::vector<const CMeshO*>& surfaces);

/// The landmark layer for the cage `surfaces`: the named layer (`named`: index into `layers`, -1 for none) when it
/// is a landmark layer with the codes `needed` and lies on the cage (or no other such layer does); else the one
/// landmark layer with those codes that lies on the cage, or the nearest one when it is clearly nearer than the
/// others. `exclude`: layers that cannot be it (the current cage). Throws InputError naming the layers and what to
/// choose when none or several fit; `param` is the parameter's name, `hint` ends the message (what else to do).
LayerChoice chooseLandmarkLayer(const std::vector<LayerRef>& layers, int named, const std::vector<int>& exclude,
                                const std::vector<const CMeshO*>& surfaces, const std::vector<int>& needed,
                                const std::string& param, const std::string& hint);

/// Why `m` cannot be the before state of `measured` (not the same mesh: another vertex count, or no faces), as a
/// clause for messages ("which is not the same mesh (...)"); empty when it can.
std::string beforeLayerProblem(const CMeshO& m, const CMeshO& measured);

/// The before layer of the measured layer `layers[current]`: the named layer when it can be (beforeLayerProblem);
/// else `recorded` (index of the layer the measured one was computed from, -1 if unknown) when it can be; else the
/// one layer that can be. Throws InputError naming the layers when none or several can.
LayerChoice chooseBeforeLayer(const std::vector<LayerRef>& layers, int named, int current, int recorded,
                              const std::string& param);

/// "layer N 'label'" for messages
std::string layerText(const LayerRef& l);

}  // namespace pectus
