// The pectus (Haller) index measured geometrically on a rib cage surface, in the project frame
// (labels.h: +y anterior, +z superior, vertebral bodies' anterior surface at x = 0, y = 0).
//  - transverse inner diameter: at the cage's lateral-most point on each side (max / min x vertex),
//    a ray along x through the bone gives the inner surface; T = x_inner(left) - x_inner(right). Where
//    that ray does not cross its side's bone twice (a sliver's tip), the next most lateral vertex serves;
//  - AP distance: the smallest distance along +y from the vertebra plane y = 0 to the first surface
//    hit (the posterior sternal surface), over rays at |x| <= 2 mm and every z (0.5 mm steps).
// Independent of how the mesh was made (works on any closed cage surface in this frame).
#pragma once
#include <optional>

#include "pectus/cmesh.h"

namespace pectus::ribcage {

struct HallerMeasure {
  double transverse = 0, ap = 0, index = 0;
  double zAp = 0;  ///< height of the smallest AP distance
  double xInnerLeft = 0, xInnerRight = 0;
};

std::optional<HallerMeasure> measureHaller(const CMeshO& m);

}  // namespace pectus::ribcage
