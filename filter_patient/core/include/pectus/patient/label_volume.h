// CT label maps (NIfTI) and the surfaces of their labels. Host-free (libnifti2 + vcglib, no Qt).
//
// A LabelVolume is what a segmentation tool writes: one integer label per voxel (0 = background) on a
// regular grid, placed in the scanner's physical frame by a 4x4 affine (voxel index i, j, k -> x, y, z in
// mm; the NIfTI sform when its code is set, else the qform, with spacing and orientation included).
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "pectus/cmesh.h"

namespace pectus::patient {

struct LabelVolume {
  std::array<int, 3> dims{0, 0, 0};       ///< voxels along i, j, k
  std::vector<std::int32_t> labels;       ///< dims[0]*dims[1]*dims[2] values, i fastest (NIfTI order)
  Eigen::Matrix4d voxelToMm = Eigen::Matrix4d::Identity();  ///< (i, j, k, 1) -> (x, y, z, 1) in mm
  std::map<int, std::string> names;       ///< label table (value -> structure name), if the file has one

  std::int32_t at(int i, int j, int k) const {
    return labels[std::size_t(i) + std::size_t(dims[0]) * (std::size_t(j) + std::size_t(dims[1]) * std::size_t(k))];
  }
  Eigen::Vector3d spacing() const;        ///< voxel edge lengths (mm): the affine's column norms
  std::vector<int> presentLabels() const; ///< the non-zero labels that occur, ascending
};

/// Reads a .nii or .nii.gz label map (integer or integer-valued float data; 3-D, or 4-D with one volume).
/// Affine: the sform when its code is set, else the qform when its code is set, else the voxel sizes
/// (pixdim) on the diagonal, i.e. index axes taken as x, y, z without orientation.
/// Units: the header's spatial unit (mm, um or m) converted to mm; unknown units are taken as mm.
/// Label names: the file's label table when it carries one (a NIfTI header extension holding an XML label
/// table, `<Label Key="1" ...>name</Label>`, with or without CDATA, as TotalSegmentator writes it), else
/// from a sidecar beside it (labelTableSidecar). Throws IOError naming the file and what is wrong
/// (missing, unreadable, not 3-D, non-integer data, singular affine).
LabelVolume readNifti(const std::string& path);

/// Reads a label table file (value -> name): one label a line ("1 rib_left_1", "1,rib_left_1", tab- or
/// semicolon-separated; ITK-SNAP's label description with the name in quotes; '#' comments and header lines
/// without a number are skipped), a JSON object {"1": "rib_left_1"}, or XML `<Label Key="1">name</Label>`.
/// Throws IOError if the file cannot be opened or has no entry.
std::map<int, std::string> readLabelTable(const std::string& path);

/// The label table file beside a NIfTI file, if one exists: for <stem>.nii[.gz] the first of <stem>.txt,
/// <stem>.csv, <stem>.json, <stem>_labels.txt, <stem>_labels.csv, <stem>_labels.json; else "".
std::string labelTableSidecar(const std::string& niftiPath);

/// Writes `v` as a NIfTI-1 file (.nii or .nii.gz by the name), int16 if the labels fit, else int32, with
/// the affine as sform and qform (code 1, scanner; the qform keeps rotation, flip and voxel sizes, not
/// shear) and units mm. When `v.names` is not empty it is written as TotalSegmentator's label table (an
/// XML CaretExtension, extension code 0), which readNifti reads back. Throws IOError if it cannot write.
void writeNifti(const LabelVolume& v, const std::string& path);

/// The closed surface of one label (all voxels == label), by marching cubes on the binary mask padded
/// by one background voxel: unsmoothed, closed, 2-manifold, outward-oriented, vertices in mm (the affine
/// applied; faces flipped when the affine mirrors). Empty if the label does not occur.
/// Vertices lie at the midpoints of the grid edges between voxel centres (one per edge, shared by its
/// faces). Where two voxels of the label touch only at an edge or a corner, their surfaces stay apart
/// (the label is taken 6-connected), so the result has no non-manifold edge or vertex. A k x l x m box of
/// voxels gives a box chamfered at its edges and corners, of volume (in voxels)
/// (k-1)(l-1)(m-1) + (k-1)(l-1) + (l-1)(m-1) + (k-1)(m-1) + ((k-1) + (l-1) + (m-1))/2 + 1/6.
void extractLabelSurface(const LabelVolume& v, int label, CMeshO& out);

}  // namespace pectus::patient
