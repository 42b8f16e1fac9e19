// A CT segmentation phantom made from the parametric rib cage: the label map a segmentation tool
// (TotalSegmentator's 'total' task) would write for that cage, without licensed patient data.
//
// Structures, each its own label (TotalSegmentator's label values and names): every rib's bone
// (rib_left_N / rib_right_N), the costal cartilages as one label (costal_cartilages), the sternum,
// one vertebral body per rib level (vertebrae_T1 ... ; an elliptic cylinder on the midline whose
// lateral surface passes through the rib pair's costovertebral joints, separated from the next by a
// disc gap of 1-2 voxels), a thin curved plate per side behind the ribs (scapula_left/right, at least
// 3 mm plus 1.5 voxels from any rib), and a few stray voxels of one rib's label at least 10 mm from
// anything. A voxel takes the structure whose implicit field is negative at its centre; where
// fields overlap the sternum wins, then a rib's bone, then the cartilages, then a vertebra.
//
// Grid: voxel index i runs to the patient's left, j posterior, k superior (as CT slices stored in
// DICOM order); the affine maps indices to the scanner frame chosen by `axes`, offset so that the
// cage frame's origin is not the scanner's.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "pectus/patient/label_volume.h"
#include "pectus/labels.h"
#include "pectus/ribcage/ribcage.h"

namespace pectus::phantom {

/// Scanner frames: RAS (+x right, +y anterior, +z superior; NIfTI's world), LPS (+x left, +y posterior,
/// +z superior; DICOM's), native (the project frame: +x left, +y anterior, +z superior).
enum class Axes { RAS, LPS, Native };
const char* axesName(Axes a);
/// the rotation part of the map from the project frame to the scanner frame
Eigen::Matrix3d axesRotation(Axes a);

struct PhantomParams {
  ribcage::RibCageParams cage;                  ///< size, index, funnel; edgeLength sets the centre curves' sampling
  Eigen::Vector3d spacing{1.0, 1.0, 1.0};       ///< voxel size (mm) along i, j, k
  Axes axes = Axes::RAS;
  Eigen::Vector3d offset{-120.0, 35.0, -800.0}; ///< the project frame's origin in the scanner frame (mm)
  double margin = 12.0;                         ///< background around the structures (mm)
  int strayVoxels = 3;
  std::uint32_t seed = 1;                       ///< stray voxel placement
};

struct Phantom {
  patient::LabelVolume volume;          ///< labels, names, voxel -> scanner mm
  Eigen::Matrix4d cageToScanner = Eigen::Matrix4d::Identity();  ///< project frame (mm) -> scanner frame (mm)
  std::vector<Landmark> landmarks;      ///< the generator's landmarks, scanner frame
  ribcage::RibCageStats stats;          ///< calibration figures of the cage
  std::vector<std::array<int, 3>> strays;  ///< voxel indices of the stray voxels
  int strayLabel = 0;
  double secondsModel = 0, secondsRaster = 0;
};

// TotalSegmentator 'total' task label values
inline int ribLabel(int side, int rib) { return side == 2 ? 91 + rib : 103 + rib; }  ///< side 2 left, 1 right
inline int vertebraLabel(int t) { return 44 - t; }                                   ///< T1 = 43 ... T12 = 32
constexpr int kSternumLabel = 116, kCartilageLabel = 117, kScapulaLeftLabel = 71, kScapulaRightLabel = 72;

/// Builds the cage model and rasterises it. Deterministic for given params (threads do not matter).
/// Throws InputError for invalid cage parameters, spacing outside [0.2, 5] mm or a grid over 2^31 voxels.
Phantom makePhantom(const PhantomParams& p, const std::function<void(const char*)>& progress = {});

}  // namespace pectus::phantom

namespace pectus::phantom {

/// A triangle as its three corners (an STL file keeps no shared vertices)
using Triangle = std::array<Eigen::Vector3d, 3>;
struct ExportedFile {
  std::string name;             ///< the file's stem: bone, sternum, costal_cartilages
  std::vector<Triangle> tris;   ///< scanner frame, mm
  bool ascii = false;           ///< written as ASCII STL
};

/// The phantom as a hospital's segmentation software exports it (../notes/patient-data.md): three surfaces.
///  - bone: the ribs, vertebrae and scapulae as one surface (fused wherever their voxels touch); the field of
///    view cut flat at the top (through the first vertebra) and the bottom (8 voxels above the lowest rib's end);
///    a closed marrow shell nested inside each rib and vertebra (the cavity's boundary, facing inward);
///    900 specks of one voxel away from the anatomy; two blocks of bone beside the vertebral column, as large
///    as a rib's piece by volume but no rib (a transverse process split off); 619 faces written twice;
///  - sternum (ASCII): manubrium and body apart, each with its marrow shell, ten two-triangle slivers near it,
///    and a patch of faces tilted through the surface (self-intersecting face pairs);
///  - costal_cartilages: every cartilage piece in one file, three of them with a hole (open edges).
/// Deterministic for a phantom and a seed.
std::vector<ExportedFile> messyExport(const Phantom& ph, std::uint32_t seed);

}  // namespace pectus::phantom
