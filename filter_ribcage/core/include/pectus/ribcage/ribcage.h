// Parametric pectus excavatum rib cage: one watertight, manifold, self-intersection-free
// triangle surface of ribs, costal cartilages and sternum, with per-face tissue labels and landmarks
// (conventions in common/include/pectus/labels.h). Host-free: vcglib CMeshO + Eigen, no Qt.
//
// Method: the cage is an implicit function (smooth union of elliptic-section tubes along the rib,
// cartilage and sternum centre curves), extracted on a sparse grid by marching tetrahedra (the zero
// set of a piecewise-linear function on a consistent Kuhn tetrahedralisation: closed, manifold,
// embedded), then decimated by quadric edge collapse to the target edge length. Each face gets the
// label of the primitive nearest to its centroid.
#pragma once
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "pectus/cmesh.h"
#include "pectus/labels.h"
#include "pectus/param_range.h"

namespace pectus::ribcage {

// The valid ranges validate() checks; the filter declares its parameters with the same constants.
inline constexpr ParamRange kAgeRange{5, 17};            ///< years
inline constexpr ParamRange kChestWidthRange{120, 320};  ///< mm
inline constexpr ParamRange kChestDepthShare{0.25, 0.7}; ///< x chest width
inline constexpr ParamRange kSpineHeightRange{120, 320}; ///< mm
inline constexpr ParamRange kRibPairsRange{10, 12};
/// the upper end; the lower end is at least the index of the same chest without funnel
inline constexpr ParamRange kHallerIndexRange{1, 12};
inline constexpr ParamRange kEdgeLengthRange{0.4, 8};    ///< mm
inline constexpr ParamRange kFunnelCenterZRange{0, 1.2}; ///< 0 jugular notch, 1 xiphisternal junction
inline constexpr double kFunnelMinSize = 20;             ///< mm, the funnel's least width and height
inline constexpr double kFunnelCenterXShare = 0.4;       ///< |funnelCenterX| <= this x funnel width
inline constexpr double kFunnelHeightShare = 0.8;        ///< funnelHeight <= this x spine height

/// The costal cartilages' cross-section.
enum class CartilageSection {
  /// the rib's own: an ellipse 0.85 x the rib's height by 1.05 x its thickness
  Rib,
  /// circular, with twice the area of the rib's section at its lateral point: the cross-section model that
  /// matched radiologists' CT masks of costal cartilage best (circle of area 2 M, M the mean rib section in
  /// the mid-coronal plane; 15 patients' MDCT, Dice 77.5 %; PMID 25027382)
  Ct,
};

struct RibCageParams {
  bool fromAge = true;      ///< size from age, else from the three explicit dimensions below
  double age = 7.0;         ///< years, [5, 17]
  double chestWidth = 0;    ///< explicit: widest inner transverse diameter of the cage (mm)
  double chestDepth = 0;    ///< explicit: sternum-to-vertebra distance without funnel (mm), at the jugular notch
  double spineHeight = 0;   ///< explicit: thoracic spine height T1-T12 (mm)
  int ribPairs = 12;        ///< [10, 12]; ribs 11 and 12 are floating (separate components)
  double hallerIndex = 4.0; ///< requested pectus index (inner transverse diameter / min sternum-vertebra distance)
  double funnelCenterX = 0;   ///< funnel centre, mm lateral (+ = patient's left)
  /// funnel centre along the sternum: 0 jugular notch, 1 xiphisternal junction (the xiphoid's tip lies near
  /// 1.14). 1.1: around the end of the sternum, where the thesis sees the depression (section 6.3) and
  /// measures and lifts it (Table 6-1's elevation of the end of the sternum); the deepest point lay on the
  /// lower sternum in 75 % of 300 patients (Kelly et al., Arch Bronconeumol 2013;49(5):196-200)
  double funnelCenterZ = 1.1;
  double funnelWidth = 80;    ///< transverse extent of the depression (mm), <= chest width
  double funnelHeight = 70;   ///< vertical extent of the depression (mm)
  double edgeLength = 2.0;    ///< target edge length (mm), [0.4, 8]
  /// smooth-union (fillet) radius between the tubes (mm), [0, 10]: between each rib's curve and the sternum
  /// and between neighbouring ribs/cartilages (a rib's bone and cartilage are one tube, no fillet there);
  /// 0: plain union (sharp junctions); negative: automatic, clamp(0.45 x rib thickness, 1.2, 3) mm
  double blend = -1;
  CartilageSection cartilageSection = CartilageSection::Rib;
};

/// Derived dimensions (mm) used by the generator.
struct Dimensions {
  double chestWidth, chestDepth, spineHeight;  ///< inner transverse diameter, rest AP distance, T1-T12
  double ribHeight, ribThickness, sternumWidth, sternumThickness, sternumLength;
};

struct RibCageStats {
  Dimensions dims{};
  double hallerRequested = 0;
  double hallerRest = 0;        ///< index of the same chest without funnel (lower bound of the valid range)
  double hallerModel = 0;       ///< measured on the implicit surface after calibration
  double funnelDepth = 0;       ///< sternal displacement at the funnel centre (mm)
  double transverseInner = 0, apMin = 0, zDeepest = 0;
  double gridSpacing = 0;
  std::size_t rawFaces = 0;     ///< faces before decimation
  int decimationRetries = 0;    ///< decimations redone (with the embedding guard) as the result intersected itself
  double secondsField = 0, secondsExtract = 0, secondsDecimate = 0, secondsLabel = 0;
};

/// The costal cartilages' section diameters (mm): along the rib's height, then along its thickness.
std::array<double, 2> cartilageDiameters(const Dimensions& d, CartilageSection s);

/// Validates params (throws pectus::InputError naming the parameter and its valid range).
Dimensions validate(const RibCageParams& p);

/// Builds the cage into `out` (cleared first) with face labels written by pectus::writeFaceLabels,
/// and returns the landmarks. progress(percent, what) may be empty.
std::vector<Landmark> generateRibCage(const RibCageParams& p, CMeshO& out, RibCageStats* stats = nullptr,
                                      const std::function<void(int, const char*)>& progress = {});

/// Names of generateTissueLayers' out[0..2]: the layer names the generator writes and the join reads.
inline constexpr std::array<const char*, 3> kTissueLayerNames{"ribs", "costal cartilage", "sternum"};

/// The same cage as one closed, labelled surface per tissue, as CT segmentation tools export them:
/// out[0] the ribs (bone), out[1] the costal cartilages, out[2] the sternum. Bone and cartilage overlap
/// by a few mm at the costochondral junctions and the cartilages reach into the sternum; there is no
/// smooth-union fillet between the tissues. Same landmarks as generateRibCage. The layers' names, in that
/// order, are kTissueLayerNames (names joinTissueLayers reads the tissue from). OwnedMesh: the caller owns
/// the three meshes and their face labels are freed with them.
std::vector<Landmark> generateTissueLayers(const RibCageParams& p, std::array<OwnedMesh, 3>& out, RibCageStats* stats = nullptr,
                                           const std::function<void(int, const char*)>& progress = {});

}  // namespace pectus::ribcage
