// MeshLab's own vcglib mesh type (CMeshO), without Qt or the MeshLab document: the algorithm cores
// work on it directly so that the adapters pass `MeshModel::cm` through without copies.
#pragma once
#ifndef MESHLAB_SCALAR
#error "MESHLAB_SCALAR must be defined (float, the ABI of Debian's MeshLab 2020.09); link pectus::vcg"
#endif
#include <common/ml_mesh_type.h>

#include <Eigen/Dense>

namespace pectus {
inline Eigen::Vector3d toEigen(const Point3m& p) { return {double(p[0]), double(p[1]), double(p[2])}; }
inline Point3m toPoint(const Eigen::Vector3d& p) { return Point3m(Scalarm(p[0]), Scalarm(p[1]), Scalarm(p[2])); }
}  // namespace pectus
