// Label maps: NIfTI read/write round trips, header variants, and the marching-cubes surfaces of labels.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <unistd.h>

#include "pectus/patient/label_volume.h"
#include "pectus/errors.h"
#include "pectus/mesh_checks.h"

using namespace pectus;
using namespace pectus::patient;
namespace fs = std::filesystem;

namespace {

fs::path tmpDir() {
  const fs::path d = fs::temp_directory_path() / ("pectus_label_volume_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

LabelVolume smallVolume(const Eigen::Matrix4d& a) {
  LabelVolume v;
  v.dims = {5, 4, 3};
  v.labels.resize(60);
  for (std::size_t i = 0; i < v.labels.size(); ++i) v.labels[i] = std::int32_t((i * 7) % 5 == 0 ? 0 : (i * 13) % 9);
  v.voxelToMm = a;
  return v;
}

Eigen::Matrix4d lpsAnisotropic() {
  // anisotropic voxels; the first index axis mirrored (LPS-like data in a RAS frame), so det < 0
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  a.topLeftCorner<3, 3>() = Eigen::Vector3d(-0.8, 0.7, 1.5).asDiagonal();
  a.block<3, 1>(0, 3) = Eigen::Vector3d(120.5, -35.25, -800);
  return a;
}

double signedVolume(const CMeshO& m) {
  double v = 0;
  for (const auto& f : m.face) {
    if (f.IsD()) continue;
    const Eigen::Vector3d a = toEigen(f.cP(0)), b = toEigen(f.cP(1)), c = toEigen(f.cP(2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

void expectClosedManifold(const CMeshO& m, const std::string& what) {
  const MeshReport r = inspectMesh(m);
  EXPECT_GT(r.faces, 0u) << what;
  EXPECT_EQ(r.boundaryEdges, 0u) << what;
  EXPECT_EQ(r.nonManifoldEdges, 0u) << what;
  EXPECT_EQ(r.nonManifoldVertices, 0u) << what;
  EXPECT_EQ(r.duplicateFaces, 0u) << what;
  EXPECT_EQ(r.unreferencedVertices, 0u) << what;
  EXPECT_EQ(r.degenerateFaces, 0u) << what;
  EXPECT_GT(signedVolume(m), 0) << what << ": not outward";
}

// vertices - edges + faces
int euler(const CMeshO& m) {
  std::set<std::pair<const void*, const void*>> edges;
  for (const auto& f : m.face)
    for (int k = 0; k < 3; ++k) {
      const void* a = f.cV(k);
      const void* b = f.cV((k + 1) % 3);
      edges.insert(a < b ? std::make_pair(a, b) : std::make_pair(b, a));
    }
  return m.vn - int(edges.size()) + m.fn;
}

double boxVolumeVoxels(int k, int l, int m) {
  const double a = k - 1, b = l - 1, c = m - 1;
  return a * b * c + a * b + b * c + a * c + (a + b + c) / 2 + 1.0 / 6.0;
}

// A NIfTI-1 file written byte by byte (no sform/qform unless given), for header variants writeNifti does not make.
void writeRawNifti(const fs::path& p, const std::vector<short>& dim, short datatype, const std::vector<char>& data,
                   char units = 2, float slope = 0, const float* srow = nullptr) {
  std::vector<char> h(352, 0);
  auto put = [&](std::size_t off, const void* src, std::size_t n) { std::memcpy(h.data() + off, src, n); };
  const int sz = 348;
  put(0, &sz, 4);
  for (std::size_t i = 0; i < dim.size(); ++i) put(40 + 2 * i, &dim[i], 2);
  put(70, &datatype, 2);
  const short bitpix = short(8 * (datatype == 16 ? 4 : datatype == 64 ? 8 : datatype == 4 ? 2 : 1));
  put(72, &bitpix, 2);
  const float pix[4] = {1.0f, 0.5f, 0.75f, 2.0f};
  put(76, pix, 16);
  const float voxOffset = 352;
  put(108, &voxOffset, 4);
  put(112, &slope, 4);
  h[123] = units;
  if (srow) {
    const short one = 1;
    put(254, &one, 2);
    put(280, srow, 48);
  }
  put(344, "n+1", 4);
  std::ofstream o(p, std::ios::binary);
  o.write(h.data(), std::streamsize(h.size()));
  o.write(data.data(), std::streamsize(data.size()));
}

template <class T>
std::vector<char> bytes(const std::vector<T>& v) {
  std::vector<char> b(v.size() * sizeof(T));
  std::memcpy(b.data(), v.data(), b.size());
  return b;
}

}  // namespace

TEST(LabelVolume, RoundTripNiiAndGzWithNamesAndMirroredAnisotropicAffine) {
  const fs::path d = tmpDir();
  for (const char* name : {"rt.nii", "rt.nii.gz"}) {
    LabelVolume v = smallVolume(lpsAnisotropic());
    v.names = {{1, "rib_left_1"}, {2, "rib_right_12"}, {5, "costal_cartilages"}, {8, "a & b <c>"}};
    const std::string p = (d / name).string();
    writeNifti(v, p);
    const LabelVolume r = readNifti(p);
    EXPECT_EQ(r.dims, v.dims) << name;
    EXPECT_EQ(r.labels, v.labels) << name;
    EXPECT_TRUE(r.voxelToMm.isApprox(v.voxelToMm, 1e-6)) << name << "\n" << r.voxelToMm;
    EXPECT_EQ(r.names, v.names) << name;
    EXPECT_NEAR(r.spacing()[0], 0.8, 1e-6);
    EXPECT_NEAR(r.spacing()[2], 1.5, 1e-6);
  }
  // a rotated affine and labels beyond int16
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  a.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
                            Eigen::Vector3d(1.25, 1.25, 2.5).asDiagonal();
  a.block<3, 1>(0, 3) = Eigen::Vector3d(-5, 6, 7);
  LabelVolume v = smallVolume(a);
  v.labels[3] = 40000;
  v.labels[4] = -3;
  writeNifti(v, (d / "big.nii.gz").string());
  const LabelVolume r = readNifti((d / "big.nii.gz").string());
  EXPECT_EQ(r.labels, v.labels);
  EXPECT_TRUE(r.voxelToMm.isApprox(a, 1e-5));
  EXPECT_TRUE(r.names.empty());
  EXPECT_EQ(r.presentLabels(), (std::vector<int>{-3, 1, 2, 3, 4, 5, 6, 7, 8, 40000}));
  fs::remove_all(d);
}

TEST(LabelVolume, HeaderVariants) {
  const fs::path d = tmpDir();
  // metres and microns are converted to mm (xyzt_units at byte 123 of the NIfTI-1 header)
  LabelVolume v = smallVolume(lpsAnisotropic());
  writeNifti(v, (d / "u.nii").string());
  for (const auto& [code, scale] : {std::pair<char, double>{1, 1000.0}, {3, 0.001}, {0, 1.0}}) {
    std::fstream f(d / "u.nii", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(123);
    f.put(code);
    f.close();
    const LabelVolume r = readNifti((d / "u.nii").string());
    Eigen::Matrix4d want = v.voxelToMm;
    want.topRows<3>() *= scale;
    EXPECT_TRUE(r.voxelToMm.isApprox(want, 1e-6)) << int(code) << "\n" << r.voxelToMm;
  }
  // integer-valued float32, 4-D with one volume, no sform/qform: pixdim on the diagonal
  writeRawNifti(d / "f.nii", {4, 2, 2, 2, 1, 1, 1, 1}, 16, bytes(std::vector<float>{0, 1, 2, 0, 0, 3, 92, 0}));
  LabelVolume r = readNifti((d / "f.nii").string());
  EXPECT_EQ(r.labels, (std::vector<std::int32_t>{0, 1, 2, 0, 0, 3, 92, 0}));
  EXPECT_TRUE(r.voxelToMm.isApprox(Eigen::Vector4d(0.5, 0.75, 2.0, 1).asDiagonal().toDenseMatrix()));
  // float64, uint16, int8 with a metre sform
  const float srow[12] = {0.001f, 0, 0, 0.1f, 0, 0.001f, 0, 0.2f, 0, 0, 0.002f, 0.3f};
  writeRawNifti(d / "d.nii", {3, 2, 1, 1, 1, 1, 1, 1}, 64, bytes(std::vector<double>{7, 0}), 1, 0, srow);
  r = readNifti((d / "d.nii").string());
  EXPECT_EQ(r.labels, (std::vector<std::int32_t>{7, 0}));
  EXPECT_NEAR(r.voxelToMm(0, 0), 1.0, 1e-5);
  EXPECT_NEAR(r.voxelToMm(2, 3), 300.0, 1e-3);
  writeRawNifti(d / "u16.nii", {3, 2, 1, 1, 1, 1, 1, 1}, 512, bytes(std::vector<std::uint16_t>{65535, 1}));
  EXPECT_EQ(readNifti((d / "u16.nii").string()).labels, (std::vector<std::int32_t>{65535, 1}));
  writeRawNifti(d / "i8.nii", {3, 2, 1, 1, 1, 1, 1, 1}, 256, bytes(std::vector<std::int8_t>{-2, 5}));
  EXPECT_EQ(readNifti((d / "i8.nii").string()).labels, (std::vector<std::int32_t>{-2, 5}));

  auto expectError = [&](const fs::path& p, const std::string& part) {
    try {
      readNifti(p.string());
      ADD_FAILURE() << p << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
    }
  };
  writeRawNifti(d / "prob.nii", {3, 2, 1, 1, 1, 1, 1, 1}, 16, bytes(std::vector<float>{0.5f, 1}));
  expectError(d / "prob.nii", "integer labels");
  writeRawNifti(d / "two.nii", {4, 2, 1, 1, 2, 1, 1, 1}, 2, bytes(std::vector<std::uint8_t>{0, 1, 1, 0}));
  expectError(d / "two.nii", "one 3-D volume");
  writeRawNifti(d / "flat.nii", {2, 2, 2, 1, 1, 1, 1, 1}, 2, bytes(std::vector<std::uint8_t>{0, 1, 1, 0}));
  expectError(d / "flat.nii", "3-D");
  expectError(d / "missing.nii.gz", "not found");
  {
    std::ofstream o(d / "junk.nii");
    o << "not a nifti file at all";
  }
  expectError(d / "junk.nii", "cannot be read");
  fs::remove_all(d);
}

TEST(LabelVolume, SidecarAndLabelTables) {
  const fs::path d = tmpDir();
  LabelVolume v = smallVolume(Eigen::Matrix4d::Identity());
  writeNifti(v, (d / "seg.nii.gz").string());
  EXPECT_TRUE(readNifti((d / "seg.nii.gz").string()).names.empty());
  {
    std::ofstream o(d / "seg.csv");
    o << "value,name\n1,rib_left_1\n2, sternum\n";
  }
  EXPECT_EQ(readNifti((d / "seg.nii.gz").string()).names, (std::map<int, std::string>{{1, "rib_left_1"}, {2, "sternum"}}));
  {
    std::ofstream o(d / "t.json");
    o << "{\"1\": \"rib_left_1\", \"117\": \"costal_cartilages\"}";
  }
  EXPECT_EQ(readLabelTable((d / "t.json").string()), (std::map<int, std::string>{{1, "rib_left_1"}, {117, "costal_cartilages"}}));
  {
    std::ofstream o(d / "itk.txt");
    o << "# ITK-SNAP Label Description File\n    0     0    0    0        0  0  0    \"Clear Label\"\n"
         "    1   255    0    0        1  1  1    \"rib left 1\"\n";
  }
  EXPECT_EQ(readLabelTable((d / "itk.txt").string()), (std::map<int, std::string>{{0, "Clear Label"}, {1, "rib left 1"}}));
  {
    std::ofstream o(d / "x.xml");
    o << "<LabelTable><Label Key=\"3\" Red=\"1\">vertebrae_T1</Label></LabelTable>";
  }
  EXPECT_EQ(readLabelTable((d / "x.xml").string()), (std::map<int, std::string>{{3, "vertebrae_T1"}}));
  {
    std::ofstream o(d / "empty.txt");
    o << "nothing here\n";
  }
  EXPECT_THROW(readLabelTable((d / "empty.txt").string()), InputError);
  fs::remove_all(d);
}

TEST(LabelSurface, BoxVolumeIsTheChamferedBox) {
  for (const auto& box : {std::array<int, 3>{1, 1, 1}, {3, 2, 1}, {4, 5, 6}, {7, 1, 3}}) {
    LabelVolume v;
    v.dims = {box[0] + 4, box[1] + 5, box[2] + 3};
    v.labels.assign(std::size_t(v.dims[0]) * v.dims[1] * v.dims[2], 0);
    for (int k = 0; k < box[2]; ++k)
      for (int j = 0; j < box[1]; ++j)
        for (int i = 0; i < box[0]; ++i)
          v.labels[std::size_t(i + 2) + std::size_t(v.dims[0]) * (std::size_t(j + 1) + std::size_t(v.dims[1]) * std::size_t(k + 2))] = 7;
    v.labels[0] = 3;  // another label in the corner
    for (const Eigen::Matrix4d& a : {Eigen::Matrix4d(Eigen::Matrix4d::Identity()), lpsAnisotropic()}) {
      v.voxelToMm = a;
      OwnedMesh m;
      extractLabelSurface(v, 7, m);
      const std::string what = "box " + std::to_string(box[0]) + "x" + std::to_string(box[1]) + "x" + std::to_string(box[2]);
      expectClosedManifold(m, what);
      EXPECT_EQ(euler(m), 2) << what;
      const double vox = std::abs(a.topLeftCorner<3, 3>().determinant());
      EXPECT_NEAR(signedVolume(m), boxVolumeVoxels(box[0], box[1], box[2]) * vox, 1e-4 * vox * box[0] * box[1] * box[2]) << what;
      // the surface lies half a voxel outside the outer voxel centres
      const Eigen::Vector3d lo = a.topLeftCorner<3, 3>() * Eigen::Vector3d(1.5, 0.5, 1.5) + a.block<3, 1>(0, 3);
      const Eigen::Vector3d hi =
          a.topLeftCorner<3, 3>() * Eigen::Vector3d(box[0] + 1.5, box[1] + 0.5, box[2] + 1.5) + a.block<3, 1>(0, 3);
      for (int d = 0; d < 3; ++d) {
        EXPECT_NEAR(m.bbox.min[d], std::min(lo[d], hi[d]), 1e-4) << what;
        EXPECT_NEAR(m.bbox.max[d], std::max(lo[d], hi[d]), 1e-4) << what;
      }
    }
  }
}

TEST(LabelSurface, EveryCubeConfigurationIsClosedAndManifold) {
  // all 2x2x2 voxel configurations (diagonal neighbours through an edge or a corner included)
  for (int cs = 1; cs < 256; ++cs) {
    LabelVolume v;
    v.dims = {2, 2, 2};
    v.labels.assign(8, 0);
    for (int c = 0; c < 8; ++c)
      if (cs >> c & 1) v.labels[std::size_t(c)] = 1;
    OwnedMesh m;
    extractLabelSurface(v, 1, m);
    expectClosedManifold(m, "configuration " + std::to_string(cs));
  }
  // two voxels touching at an edge, at a corner: two separate octahedra
  for (const auto& other : {std::array<int, 3>{1, 1, 0}, {1, 1, 1}}) {
    LabelVolume v;
    v.dims = {2, 2, 2};
    v.labels.assign(8, 0);
    v.labels[0] = 4;
    v.labels[std::size_t(other[0] + 2 * other[1] + 4 * other[2])] = 4;
    OwnedMesh m;
    extractLabelSurface(v, 4, m);
    expectClosedManifold(m, "diagonal pair");
    EXPECT_EQ(m.fn, 16);
    EXPECT_EQ(m.vn, 12);
    EXPECT_NEAR(signedVolume(m), 2.0 / 6.0, 1e-6);
  }
}

TEST(LabelSurface, RandomBlobsAreClosedAndManifold) {
  std::mt19937 rng(12345);
  for (int trial = 0; trial < 200; ++trial) {
    LabelVolume v;
    v.dims = {9 + trial % 4, 8, 7 + trial % 3};
    v.labels.assign(std::size_t(v.dims[0]) * v.dims[1] * v.dims[2], 0);
    const double density = 0.2 + 0.6 * (trial % 5) / 4.0;
    for (auto& l : v.labels) l = (rng() % 1000) < density * 1000 ? 1 + int(rng() % 2) : 0;
    v.voxelToMm = trial % 2 ? lpsAnisotropic() : Eigen::Matrix4d(Eigen::Matrix4d::Identity());
    for (int label : {1, 2}) {
      OwnedMesh m;
      extractLabelSurface(v, label, m);
      expectClosedManifold(m, "blob " + std::to_string(trial));
      // Euler characteristic is even for closed orientable surfaces
      EXPECT_EQ(euler(m) % 2, 0);
    }
  }
}

TEST(LabelSurface, AbsentLabelGivesAnEmptyMesh) {
  LabelVolume v = smallVolume(Eigen::Matrix4d::Identity());
  OwnedMesh m;
  extractLabelSurface(v, 99, m);
  EXPECT_EQ(m.fn, 0);
  EXPECT_EQ(m.vn, 0);
}
