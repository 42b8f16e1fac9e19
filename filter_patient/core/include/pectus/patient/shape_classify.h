// Internal to the patient core: layers whose names say nothing ('Segment_1', 'Segment_2', ... as 3D Slicer
// exports them) classified by their shape and by where they lie among the others. It works in the layers' own
// frame and units (it runs before the frame and the units are found): every length is compared with the size
// of the whole, every direction is taken from the anatomy found so far.
//
// In order: a layer of many long pieces, or one piece as wide as the cage, is bone (ribs, maybe fused to the
// spine); a layer of many small bar-like pieces is the costal cartilages; the sternum is the elongated one-piece
// layer nearest the cartilages' centre. The sternum and the centre of the whole then give provisional anterior,
// long and lateral axes, in which the rest is placed: compact blocks (or a column of them) on the midline
// behind the centre are vertebrae, thin elongated pieces beside the midline that reach behind the centre are
// ribs, thin bars wholly in front are cartilages, plates behind and beside the cage are scapulae (left out).
// Anything else stays Unknown and is left out. Layers named by their name are kept as they are and serve as
// anchors (a named sternum or cartilage is used instead of searching for one).
#pragma once
#include <string>
#include <vector>

#include "pectus/patient/prepare.h"
#include "pectus/patient/soup.h"

namespace pectus::patient {

struct LayerToClassify {
  std::string name;
  const Soup* soup = nullptr;  ///< welded
  NameClass cls;               ///< from the name; Kind::Unknown for the layers to classify by shape
};

/// The class of every layer: the named ones as given, the Unknown ones by shape (Kind::Unknown where the shape
/// settles nothing). Each decision goes to `log` as one line naming the layer and the shape that decided it.
/// Throws InputError ending in "rename the layers: ..." when the cartilages or the sternum are found neither by
/// name nor by shape, or when two layers are equally good sternums.
std::vector<NameClass> classifyByShape(const std::vector<LayerToClassify>& layers, std::vector<std::string>& log);

}  // namespace pectus::patient
