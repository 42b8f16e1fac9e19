// Internal: the rib cage's centre curves (anatomy) and the implicit field built on them.
#pragma once
#include <array>
#include <functional>
#include <vector>

#include <Eigen/Dense>

#include "pectus/ribcage/ribcage.h"

namespace pectus::ribcage {

/// A tube with an elliptic cross-section along a polyline: semi-axis ra along n, rb along b.
struct Curve {
  std::vector<Eigen::Vector3d> c, n, b;
  std::vector<double> ra, rb, u;  ///< u: normalised arc length in [0,1]
  bool capStart = true, capEnd = true;
  int side = 0, rib = 0;          ///< rib curves (rib > 0); sternum: rib = 0
  double uCartilage = 2;          ///< rib: u where the costal cartilage starts (> 1: none)
  std::array<double, 3> sternumSplit{};  ///< sternum: u of manubrium|body and body|xiphoid junctions, tip
};

/// Anatomy of one cage (rest geometry + funnel), all in the project frame (mm, labels.h).
struct CageModel {
  Dimensions d{};
  int ribPairs = 12;
  double delta = 0;                     ///< vertebral level spacing
  double zNotch = 0, zMS = 0, zXJ = 0, zTip = 0;  ///< sternum: jugular notch, manubriosternal, xiphisternal, tip
  double funnelDepth = 0, fx = 0, fz = 0, fw = 0, fh = 0;
  double blend = 2;                     ///< smooth-union radius (mm), 0: plain union
  CartilageSection cartilageSection = CartilageSection::Rib;
  double spacing = 1.5;                 ///< polyline sampling
  std::vector<Curve> curves;            ///< ribs (both sides) then the sternum (last)
  /// funnel displacement weight at rest position (x, y, z)
  double funnel(double x, double y, double z) const;
};

/// the automatic smooth-union radius (RibCageParams::blend < 0) of a cage of these dimensions (mm)
double autoBlend(const Dimensions& d);

CageModel buildModel(const Dimensions& d, const RibCageParams& p, double funnelDepth, double spacing);

/// The anatomy generateRibCage builds for p (validated; funnel depth calibrated to p.hallerIndex on the
/// implicit surface), without extracting a surface: for tools that sample the model themselves. `stats`
/// receives the calibration figures (no surface figures), `landmarks` what generateRibCage returns.
CageModel buildCalibratedModel(const RibCageParams& p, RibCageStats* stats = nullptr, std::vector<Landmark>* landmarks = nullptr);

/// The rest cage's (no funnel) anatomy, measured on the model to compare it with published figures
/// (docs/validation.md, "Anatomy of the generated cage"). Lengths run along the centre lines (mm).
struct Anatomy {
  Dimensions dims{};
  double restIndex = 0;       ///< pectus index of the chest without funnel
  double sternumLength = 0;   ///< jugular notch to xiphoid tip
  std::array<double, 2> cartilage{};  ///< costal cartilage section diameters (cartilageDiameters)
  struct Rib {
    double length = 0;        ///< costovertebral joint to the sternum's edge
    double cartilage = 0;     ///< costochondral junction to the sternum's edge
    double anteriorShare = 0; ///< the cartilage's share of the anterior rib (lateral point to the sternum's edge)
  };
  std::array<Rib, 7> ribs{};  ///< the right ribs 1-7
  double sternumHalfWidth = 0;  ///< where the ribs' lengths end: half the sternum body's width
  double fifthJunction = 0;   ///< the right 5th costochondral junction's lateral distance from the midline
};
/// Validates p (InputError as validate); the index and funnel parameters are not used.
Anatomy measureAnatomy(const RibCageParams& p);

/// Spatial hash of the curves' segments and the smooth-union field (negative inside).
class CageField {
 public:
  /// keep(curve, i): use segment i of the curve (all when empty), e.g. the segments of one tissue
  explicit CageField(const CageModel& m, double cell = 5.0, const std::function<bool(const Curve&, int)>& keep = {});
  double operator()(const Eigen::Vector3d& p) const;
  /// nearest primitive at p: curve index and the u parameter there
  std::pair<int, double> nearest(const Eigen::Vector3d& p) const;
  Eigen::Vector3d boxMin() const { return lo_; }
  Eigen::Vector3d boxMax() const { return hi_; }
  /// segments' influence boxes (for sparse extraction)
  struct Seg { int curve, i; Eigen::Vector3d lo, hi; };
  const std::vector<Seg>& segments() const { return segs_; }

 private:
  double segValue(const Seg& s, const Eigen::Vector3d& p, double* u = nullptr) const;
  const CageModel& m_;
  double cell_;
  Eigen::Vector3d lo_, hi_;
  std::array<int, 3> n_{};
  std::vector<std::vector<int>> grid_;
  std::vector<Seg> segs_;
};

}  // namespace pectus::ribcage
