// Host-free cores of the thoracic volume filters and of the Nuss bar planner (thesis chapter 6.3): the
// slice (intersection) method, the Ferguson bicubic envelope (surface approximation) method, and the
// pectus indices.
// Frame (common/include/pectus/labels.h): millimetres, +z superior, +y anterior, +x patient's left;
// the body's long axis is z. Volumes are in mm^3 (1 cm^3 = 1000 mm^3).
#pragma once
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "pectus/cmesh.h"
#include "pectus/param_range.h"
#include "pectus/surface.h"

namespace pectus::vol {

// Valid ranges of SliceParams and EnvelopeParams; the filters declare their parameters with the same
// constants. sliceVolume and fergusonEnvelope check the lower ends only: the upper ends bound what a user
// asks for, and the cores' other callers go beyond them with values that scale with the model: the envelope
// filter's coverage probe slices at an eighth of the range whatever its height, the volume fuzz target
// takes the envelope's minimum step as 1/64 of the model's width.
inline constexpr ParamRange kSpacingRange{0.01, 1000};    ///< SliceParams::spacing (mm)
inline constexpr ParamRange kResolutionRange{16, 20000};  ///< SliceParams::resolution (pixels)
inline constexpr ParamRange kRaysRange{16, 100000};       ///< boundary rays of a slice
inline constexpr ParamRange kPatchesLongRange{1, 200};    ///< EnvelopeParams::nLong
inline constexpr ParamRange kPatchesAroundRange{3, 200};  ///< EnvelopeParams::mAround
inline constexpr ParamRange kMinStepRange{1e-4, 1e4};     ///< EnvelopeParams::minStep (mm)

/// A triangle soup in double precision (what every core here reads): the cores' surface type
using Soup = pectus::Surface;
/// Live faces of m (vertex indices of the vcg vertex vector), without the faces labelled as the vertebral
/// column (part kVertebralColumn of labels.h: the column a prepared patient cage keeps as the FE support);
/// throws InputError on NaN coordinates.
Soup soupFromMesh(const CMeshO& m, const std::string& layer);

/// Signed enclosed volume of a closed, consistently oriented triangle mesh by the divergence
/// theorem (sum of signed tetrahedra to the centroid), mm^3; positive for outward normals.
double divergenceVolume(const Soup& s);

/// Progress callback: percent [0,100] and a label; may be empty.
using Progress = std::function<void(int, const char*)>;

/// The measured height range [zLo, zHi] along z; throws InputError when it is degenerate.
struct Range {
  double zLo = 0, zHi = 0;
};
void requireRange(const Range& r, const std::string& what);

/// Before/after pair check: same vertex count and the same frame (comparable bounding boxes, and
/// most vertices not moved by more than a tenth of the size: an FE correction moves the anterior
/// wall, not the whole model). Throws InputError naming both layers, TopologyError when the before layer has
/// no faces.
void requireComparablePair(const Soup& before, const Soup& after, const std::string& beforeName,
                           const std::string& afterName);

// -------------------------------------------------------------------------------------------
// Slices: plane z = const cut with the cage, and the intrathoracic region of the slice.
//
// Gap-closing rule (the thesis segmented the slices by hand): seen from the slice centroid c (the
// length-weighted centroid of the cut segments), the intrathoracic region is star-shaped; along
// each of K rays (uniform angles) its boundary is the NEAREST cut segment (the inner side of every
// rib, cartilage, sternum or vertebra section). Rays that hit nothing pass through a gap between
// sections: their radius is filled by a cubic Hermite interpolation in the angle between the two
// neighbouring hit rays, with the boundary slopes dr/dtheta taken by least squares over up to four
// hit rays on each side (so an intercostal gap is bridged by the curve continuing the walls), kept
// between the chord joining the gap's end points (no concave dent) and the larger end radius (no
// balloon). Gaps wider than 60 degrees (a missing spine, the abdominal opening) are closed by the
// chord. Before filling, rays that see an outer wall through a gap (short runs lying outward of the
// chord of their neighbours, and run ends jumping outward of the run's linear trend by > 1 %) are
// treated as gaps. The region is the closed polygon through the K boundary points; a slice with
// fewer than 3 hit rays is empty.

struct Seg2 {
  Eigen::Vector2d a, b;
};

struct SliceRegion {
  double z = 0;
  std::vector<Seg2> segments;         ///< the cut of the cage by the plane
  Eigen::Vector2d centroid{0, 0};
  std::vector<double> radius;         ///< K boundary radii (after gap filling)
  std::vector<char> hit;              ///< K flags: ray hit a section
  std::vector<Eigen::Vector2d> polygon;  ///< K boundary points (counter-clockwise)
  int hits = 0;
  bool empty() const { return hits < 3; }
  double coverage() const { return hit.empty() ? 0.0 : double(hits) / double(hit.size()); }
  double polygonArea() const;         ///< exact shoelace area of the polygon
};

/// Cuts `s` with the planes z = zs[k] (faces bucketed once), returns the segments per plane.
std::vector<std::vector<Seg2>> cutPlanes(const Soup& s, const std::vector<double>& zs);
/// The intrathoracic region of one cut (rule above) with K rays, cast from the segments' centroid or
/// from `seed` (a point known to be inside, e.g. between the vertebra and the sternum of a deep funnel,
/// where the centroid can fall in front of the sternum).
SliceRegion regionFromSegments(double z, std::vector<Seg2> segments, int rays,
                               const std::optional<Eigen::Vector2d>& seed = std::nullopt);

struct SliceParams {
  double spacing = 2.6;   ///< plane spacing, mm (thesis 2.6)
  int resolution = 512;   ///< raster size (pixels along the longer side of the slices' common box)
  int rays = 720;         ///< K rays of the boundary rule
};

struct SliceResult {
  double volume = 0;       ///< mm^3: sum over slices of raster area x spacing
  double polygonVolume = 0;  ///< mm^3: the same with the polygons' exact areas (raster check)
  double spacingUsed = 0;  ///< spacing adjusted so that the planes fill [zLo,zHi] (midpoint rule)
  double pixel = 0;        ///< raster pixel size, mm
  int slices = 0;
  int emptySlices = 0;     ///< slices whose cut encloses no area (bridged ones and those at the ends)
  int bridgedSlices = 0;   ///< empty slices between two slices with area: region interpolated
  int endEmptySlices = 0;  ///< empty slices below the first or above the last slice with area: zero area
  double minCoverage = 1;  ///< smallest fraction of hit rays over the non-empty slices
  std::vector<double> z, area;
  std::vector<char> bridged;  ///< per slice: 1 when its area is bridged
};

/// Slice method (thesis 6.3.1): planes at the midpoints of ceil((zHi-zLo)/spacing) equal layers,
/// each region rasterised on a common resolution x resolution grid (pixel centres inside the region
/// polygon are counted) and summed as area x layer thickness. Throws InputError when no plane cuts
/// anything.
///
/// Bridging: a slice whose cut encloses no area (a plane between two ribs, horizontal or sloping, or
/// through a missing or thin rib) lying between two slices with area is bridged: its region is
/// interpolated ray by ray, linearly in z, between the nearest slices with area below and above (the
/// boundary point on each ray moves from the lower region's to the upper region's), then rasterised
/// like the others. Empty slices below the first or above the last slice with area are not bridged
/// (nothing to interpolate): they count as zero area (endEmptySlices).
SliceResult sliceVolume(const Soup& s, const Range& range, const SliceParams& p, const Progress& progress = {});

// -------------------------------------------------------------------------------------------
// Ferguson envelope (thesis 6.3.2)

struct EnvelopeParams {
  int nLong = 16;            ///< n patches along z
  int mAround = 16;          ///< m patches around the axis
  double initialStep = 0;    ///< first radial step, mm (0: a quarter of the start radius)
  double minStep = 0.05;     ///< convergence: stop after the step falls below this, mm
  bool smoothing = true;     ///< eq. 6-1 between the step levels
  std::optional<Eigen::Vector3d> sternumEnd;  ///< key points near it are not smoothed (thesis)
  int binsPerPatch = 6;      ///< samples kept per patch: the outermost one in each of bins x bins cells
  int tessellation = 8;      ///< samples per patch side of the output mesh
};

struct Envelope {
  int n = 0, m = 0;           ///< patch rows (including the guard rows) and columns
  double zLo = 0, zHi = 0;    ///< z of ring 0 and ring n
  int row0 = 0, row1 = 0;     ///< the measured patch rows [row0, row1): volume and tessellation
  Eigen::Vector2d axis{0, 0};
  std::vector<double> L;     ///< (n+1) x m radii, row-major by ring
  std::vector<double> phi;   ///< m angles
  Eigen::Vector3d key(int i, int j) const;
  /// surface point and partial derivatives of patch (i,j) at (u,v) in [0,1]^2
  Eigen::Vector3d eval(int i, int j, double u, double v, Eigen::Vector3d* Su = nullptr,
                       Eigen::Vector3d* Sv = nullptr) const;
  /// radius of the surface along the radial ray at angle `angle`, height z (Newton-Raphson)
  double rayRadius(double angle, double z, int* iterations = nullptr) const;
  /// volume enclosed by the measured rows and planar caps (eqs. 6-2, 6-3), Gauss-Legendre quadrature exact for the patches
  double volume() const;
  /// closed triangle mesh (lateral surface t x t per patch, fan caps), outward oriented
  Soup tessellate(int t) const;
};

struct EnvelopeResult {
  Envelope env;
  double volume = 0;        ///< mm^3 (parametric, eq. 6-3)
  int samples = 0;          ///< reduced samples used
  int singular = 0;         ///< singular key points tied to a neighbour
  int moves = 0, levels = 0, cutTests = 0;
  int touching = 0;         ///< key points held by the cage at the last level
};

/// Throws InputError when nothing lies in the range or no key point can touch the cage.
EnvelopeResult fergusonEnvelope(const Soup& s, const Range& range, const EnvelopeParams& p,
                                const Progress& progress = {});

// -------------------------------------------------------------------------------------------
// Pectus indices on one slice

struct IndexInputs {
  std::optional<double> level;              ///< z of the measured slice (else automatic)
  std::optional<double> midlineX;           ///< x of the sternum midline (else the slice centroid)
  std::optional<double> spineY;             ///< y of the vertebra's anterior surface (else measured)
  Range searchRange;                        ///< automatic level: search range
  double searchSpacing = 2.0;
  int rays = 720;
};

struct PectusIndex {
  double z = 0;
  double transverse = 0;    ///< inner transverse diameter, mm
  double apMin = 0;         ///< sternum (posterior surface) to vertebra (anterior surface), mm
  double apMax = 0;         ///< anterior-most inner chest wall to vertebra, mm
  double haller = 0;        ///< transverse / apMin
  double correction = 0;    ///< (apMax - apMin) / apMax x 100 %
  bool sternumMeasured = false, spineMeasured = false;
};

PectusIndex pectusIndex(const Soup& s, const IndexInputs& in);
/// the index on an already cut slice
PectusIndex pectusIndexOnSlice(const SliceRegion& r, const std::optional<double>& midlineX,
                               const std::optional<double>& spineY);

}  // namespace pectus::vol
