// Import of segmentation mesh files and folders (ct_import.h): every format on small files written here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "pectus/patient/ct_import.h"
#include "temp_dir.h"
#include "pectus/errors.h"

namespace fs = std::filesystem;
using namespace pectus::patient;
using pectus::patient::testing::errorOf;
using pectus::patient::testing::TempDir;

namespace {


// the unit cube: 8 corners, 12 outward triangles
const float kCube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kCubeTris[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                              {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

std::string binaryStl(const std::string& header, int tris = 12, bool nan = false) {
  std::string h = header;
  h.resize(80, ' ');
  std::string s = h;
  const std::uint32_t n = std::uint32_t(tris);
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (int t = 0; t < tris; ++t) {
    float rec[12] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) rec[3 + 3 * k + c] = kCube[kCubeTris[t % 12][k]][c];
    if (nan && t == 0) rec[3] = std::nanf("");
    s.append(reinterpret_cast<const char*>(rec), sizeof rec);
    s.append(2, '\0');
  }
  return s;
}

std::string asciiStl() {
  std::string s = "solid cube\n";
  for (const auto& t : kCubeTris) {
    s += "  facet normal 0 0 0\n    outer loop\n";
    for (int k = 0; k < 3; ++k)
      s += "      vertex " + std::to_string(kCube[t[k]][0]) + " " + std::to_string(kCube[t[k]][1]) + " " +
           std::to_string(kCube[t[k]][2]) + "\n";
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid cube\n";
}

std::string cubeVertices(const char* extra = "") {
  std::string s;
  for (const auto& v : kCube)
    s += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + extra + "\n";
  return s;
}

// the cube as six quads, in the OBJ index forms i, i/t, i//n, i/t/n and negative
std::string objCube() {
  std::string s = "# cube\r\nmtllib cube.mtl\r\no cube\r\ng faces\r\n";
  for (const auto& v : kCube)
    s += "v " + std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + " 0.5 0.2 0.1\r\n";
  s += "vt 0 0\r\nvt 1 0\r\nvt 1 1\r\nvn 0 0 1\r\ns off\r\n";
  s += "f 1 4 3 2\r\n";                   // bottom (z = 0)
  s += "f 5/1 6/2 7/3 8/1\r\n";           // top
  s += "f 1//1 2//1 6//1 5//1\r\n";       // y = 0
  s += "f 2/1/1 3/2/1 7/3/1 6/1/1\r\n";   // x = 1
  s += "f -6 -5 -1 -2\r\n";               // y = 1: 3 4 8 7
  s += "f -8/1/1 -4/2/1 -1/3/1 -5/1/1";   // x = 0: 1 5 8 4, no trailing newline
  return s;
}

std::string offCube() {
  std::string s = "OFF\n# cube\n8 6 0\n";
  for (const auto& v : kCube) s += std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
  s += "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n";
  return s;
}

std::string plyCube(bool binary) {
  std::string s = std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") +
                  " 1.0\ncomment cube\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 12\nproperty list uchar int vertex_indices\nend_header\n";
  if (!binary) {
    for (const auto& v : kCube) s += std::to_string(v[0]) + " " + std::to_string(v[1]) + " " + std::to_string(v[2]) + "\n";
    for (const auto& t : kCubeTris) s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
    return s;
  }
  for (const auto& v : kCube) s.append(reinterpret_cast<const char*>(v), 12);
  for (const auto& t : kCubeTris) {
    s += char(3);
    s.append(reinterpret_cast<const char*>(t), 12);
  }
  return s;
}

void expectCube(const CMeshO& m, const std::string& what) {
  EXPECT_EQ(m.fn, 12) << what;
  EXPECT_EQ(m.vn, 8) << what << ": the corners shared";
  EXPECT_NEAR(m.bbox.Dim()[0], 1.0, 1e-6) << what;
  EXPECT_EQ(countComponents(m), 1) << what;
}

}  // namespace

TEST(CtImport, BinaryStlSharesVertices) {
  TempDir d;
  pectus::OwnedMesh m;
  MeshFileStats st;
  readMeshFile(d.file("cube.stl", binaryStl("binary cube")), m, st);
  expectCube(m, "binary STL");
  EXPECT_EQ(st.format, "binary STL");
  EXPECT_EQ(st.trianglesRead, 12);
  EXPECT_EQ(st.mergedVertices, 36 - 8);
}

TEST(CtImport, BinaryStlWhoseHeaderStartsWithSolid) {
  TempDir d;
  pectus::OwnedMesh m;
  MeshFileStats st;
  readMeshFile(d.file("cube.STL", binaryStl("solid exported by a CAD tool")), m, st);
  EXPECT_EQ(st.format, "binary STL");
  expectCube(m, "binary STL with a 'solid' header");
}

TEST(CtImport, AsciiStl) {
  TempDir d;
  pectus::OwnedMesh m;
  MeshFileStats st;
  readMeshFile(d.file("cube.stl", asciiStl()), m, st);
  EXPECT_EQ(st.format, "ASCII STL");
  expectCube(m, "ASCII STL");
}

TEST(CtImport, StlTruncatedOrNotStl) {
  TempDir d;
  pectus::OwnedMesh m;
  std::string bin = binaryStl("cube");
  bin.resize(bin.size() - 7);
  const std::string e = errorOf([&] { readMeshFile(d.file("cut.stl", bin), m); });
  EXPECT_NE(e.find("cut.stl"), std::string::npos) << e;
  EXPECT_NE(e.find("truncated"), std::string::npos) << e;
  std::string ascii = asciiStl();
  ascii.resize(ascii.size() / 2);
  const std::string e2 = errorOf([&] { readMeshFile(d.file("cut_ascii.stl", ascii), m); });
  EXPECT_NE(e2.find("cut_ascii.stl"), std::string::npos) << e2;
}

TEST(CtImport, NonFiniteFacesDroppedAndCounted) {
  TempDir d;
  pectus::OwnedMesh m;
  MeshFileStats st;
  readMeshFile(d.file("nan.stl", binaryStl("cube", 12, true)), m, st);
  EXPECT_EQ(st.nonFiniteFaces, 1);
  EXPECT_EQ(m.fn, 11);
  EXPECT_EQ(m.vn, 8);
  const std::string e = errorOf([&] {
    readMeshFile(d.file("allnan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), m);
  });
  EXPECT_NE(e.find("no faces with finite coordinates"), std::string::npos) << e;
}

TEST(CtImport, DuplicateFacesAreKept) {
  TempDir d;
  pectus::OwnedMesh m;
  readMeshFile(d.file("dup.obj", cubeVertices() + "v 5 5 5\nf 1 2 3\nf 1 2 3\nf 3 2 1\n"), m);
  EXPECT_EQ(m.fn, 3) << "the import does not repair";
  EXPECT_EQ(m.vn, 3) << "the unused vertices are removed";
}

TEST(CtImport, ObjQuadsNegativeIndicesAndSlashes) {
  TempDir d;
  pectus::OwnedMesh m;
  MeshFileStats st;
  readMeshFile(d.file("cube.obj", objCube()), m, st);
  EXPECT_EQ(st.format, "OBJ");
  expectCube(m, "OBJ with quads, v/vt/vn and negative indices, CRLF, no final newline");
}

TEST(CtImport, ObjBadIndexNamesFileAndLine) {
  TempDir d;
  pectus::OwnedMesh m;
  const std::string e = errorOf([&] { readMeshFile(d.file("bad.obj", cubeVertices() + "f 1 2 3\nf 1 2 9\n"), m); });
  EXPECT_NE(e.find("bad.obj"), std::string::npos) << e;
  EXPECT_NE(e.find("line 10"), std::string::npos) << e;
  EXPECT_NE(e.find("vertex 9"), std::string::npos) << e;
  const std::string e0 = errorOf([&] { readMeshFile(d.file("zero.obj", cubeVertices() + "f 0 1 2\n"), m); });
  EXPECT_NE(e0.find("line 9"), std::string::npos) << e0;
  const std::string en = errorOf([&] { readMeshFile(d.file("neg.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n"), m); });
  EXPECT_NE(en.find("line 3"), std::string::npos) << en;
  const std::string ev = errorOf([&] { readMeshFile(d.file("v.obj", "v 0 0\n"), m); });
  EXPECT_NE(ev.find("line 1"), std::string::npos) << ev;
}

TEST(CtImport, PlyAsciiAndBinary) {
  TempDir d;
  pectus::OwnedMesh m;
  readMeshFile(d.file("a.ply", plyCube(false)), m);
  expectCube(m, "ASCII PLY");
  readMeshFile(d.file("b.ply", plyCube(true)), m);
  expectCube(m, "binary PLY");
}

TEST(CtImport, OffQuads) {
  TempDir d;
  pectus::OwnedMesh m;
  readMeshFile(d.file("cube.off", offCube()), m);
  expectCube(m, "OFF with quads");
}

TEST(CtImport, Errors) {
  TempDir d;
  pectus::OwnedMesh m;
  std::string e = errorOf([&] { readMeshFile((d.p / "missing.stl").string(), m); });
  EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
  e = errorOf([&] { readMeshFile(d.file("cube.xyz", "0 0 0\n"), m); });
  EXPECT_NE(e.find("unknown extension '.xyz'"), std::string::npos) << e;
  e = errorOf([&] { importSegmentation(d.file("cube.vtk", "x")); });
  EXPECT_NE(e.find("unknown extension"), std::string::npos) << e;
  e = errorOf([&] { readMeshFile(d.file("empty.obj", "# nothing\nv 0 0 0\n"), m); });
  EXPECT_NE(e.find("no faces"), std::string::npos) << e;
  e = errorOf([&] { readMeshFile(d.file("empty.stl", binaryStl("none", 0)), m); });
  EXPECT_NE(e.find("no faces"), std::string::npos) << e;
  e = errorOf([&] { importSegmentation((d.p / "nowhere").string()); });
  EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
}

TEST(CtImport, EmptyFolderListsWhatItFound) {
  TempDir d;
  fs::create_directories(d.p / "empty");
  std::string e = errorOf([&] { importSegmentation((d.p / "empty").string()); });
  EXPECT_NE(e.find("found nothing"), std::string::npos) << e;
  d.file("notes.md", "x");
  d.file("scan.dcm", "x");
  e = errorOf([&] { importSegmentation(d.p.string()); });
  EXPECT_NE(e.find("notes.md"), std::string::npos) << e;
  EXPECT_NE(e.find("scan.dcm"), std::string::npos) << e;
}

TEST(CtImport, FolderInNameOrder) {
  TempDir d;
  d.file("rib_left_3.stl", binaryStl("solid rib"));
  d.file("b_sternum.obj", objCube());
  d.file("a_cartilage.ply", plyCube(true));
  d.file("costal.off", offCube());
  d.file("README.txt", "notes");
  ImportReport rep;
  std::vector<int> progress;
  const auto s = importSegmentation(d.p.string(), {}, &rep, [&](int pc, const char*) { progress.push_back(pc); });
  ASSERT_EQ(s.size(), 4u);
  EXPECT_EQ(s[0].name, "a_cartilage");
  EXPECT_EQ(s[1].name, "b_sternum");
  EXPECT_EQ(s[2].name, "costal");
  EXPECT_EQ(s[3].name, "rib_left_3");
  for (const auto& x : s) {
    EXPECT_EQ(x.mesh->fn, 12) << x.name;
    EXPECT_EQ(x.mesh->vn, 8) << x.name;
    EXPECT_EQ(x.label, 0);
  }
  EXPECT_EQ(fs::path(s[3].source).filename(), "rib_left_3.stl");
  ASSERT_EQ(rep.lines.size(), 5u);
  EXPECT_EQ(rep.lines[3].rfind("rib_left_3: 12 faces, 8 vertices, 1 component, from rib_left_3.stl", 0), 0u) << rep.lines[3];
  EXPECT_NE(rep.lines[3].find("1.0 x 1.0 x 1.0"), std::string::npos) << rep.lines[3];
  EXPECT_NE(rep.lines[4].find("README.txt"), std::string::npos) << rep.lines[4];
  EXPECT_GE(progress.size(), 4u);
  EXPECT_EQ(progress.back(), 100);
}

TEST(CtImport, OneFileAndItsName) {
  TempDir d;
  const auto s = importSegmentation(d.file("rib_right_12.STL", asciiStl()));
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "rib_right_12");
}

TEST(CtImport, FolderWithABadFileFailsNamingIt) {
  TempDir d;
  d.file("a.stl", binaryStl("a"));
  d.file("b.obj", "v 0 0 0\nf 1 2 3\n");
  const std::string e = errorOf([&] { importSegmentation(d.p.string()); });
  EXPECT_NE(e.find("b.obj"), std::string::npos) << e;
}

TEST(CtImport, StructureNames) {
  EXPECT_EQ(structureName("/x/rib_left_3.nii.gz"), "rib_left_3");
  EXPECT_EQ(structureName("rib_left_3.NII"), "rib_left_3");
  EXPECT_EQ(structureName("/x/y/sternum.obj"), "sternum");
  EXPECT_EQ(structureName("a.b.ply"), "a.b");
  EXPECT_EQ(structureName("noext"), "noext");
}

TEST(CtImport, LabelTables) {
  auto t = parseLabelTable("1 rib_left_1\n2,rib_left_2\n3=sternum\n");
  EXPECT_EQ(t.size(), 3u);
  EXPECT_EQ(t[2], "rib_left_2");
  EXPECT_EQ(t[3], "sternum");
  t = parseLabelTable("1 rib_left_1; 2 rib_left_2");
  EXPECT_EQ(t.size(), 2u);
  t = parseLabelTable("# Slicer\n0 Background 0 0 0 0\n1 rib_left_1 255 0 0 255\n5 sternum 0 0 255 255\n");
  EXPECT_EQ(t.size(), 2u);
  EXPECT_EQ(t[5], "sternum");
  t = parseLabelTable(R"({"1": "rib_left_1", "2": "rib_left_2"})");
  EXPECT_EQ(t[2], "rib_left_2");
  t = parseLabelTable(R"({"rib_left_1": 1, "sternum": 7})");
  EXPECT_EQ(t[7], "sternum");
  t = parseLabelTable("    1   255    0    0        1  1  1    \"rib left 1\"\n");
  EXPECT_EQ(t[1], "rib left 1");
  TempDir d;
  const std::string csv = d.file("labels.csv", "value,name\r\n1,rib_left_1\r\n2;rib_left_2\r\n");
  t = parseLabelTable(csv);
  EXPECT_EQ(t.size(), 2u);
  EXPECT_EQ(t[1], "rib_left_1");
  const std::string e = errorOf([&] { parseLabelTable("1 a\nb c\n"); });
  EXPECT_NE(e.find("b c"), std::string::npos) << e;
  const std::string e2 = errorOf([&] { parseLabelTable("1 a\n1 b\n"); });
  EXPECT_NE(e2.find("named twice"), std::string::npos) << e2;
}
