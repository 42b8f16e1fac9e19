// Import of NIfTI label maps and mask files (ct_import.h over label_volume.h): label tables, naming,
// minimum voxel counts, TotalSegmentator-style folders of masks. The files are written with writeNifti.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "pectus/patient/ct_import.h"
#include "temp_dir.h"
#include "pectus/patient/label_volume.h"
#include "pectus/errors.h"

namespace fs = std::filesystem;
using namespace pectus::patient;
using pectus::patient::testing::errorOf;
using pectus::patient::testing::TempDir;

namespace {


/// 12 x 8 x 6 voxels of 0.8 x 0.8 x 1.5 mm; boxes of the given labels side by side along i
LabelVolume boxes(const std::vector<std::pair<int, int>>& labelAndWidth) {
  LabelVolume v;
  v.dims = {12, 8, 6};
  v.labels.assign(12 * 8 * 6, 0);
  v.voxelToMm.diagonal() << 0.8, 0.8, 1.5, 1.0;
  int i0 = 1;
  for (const auto& [label, w] : labelAndWidth) {
    for (int k = 1; k < 5; ++k)
      for (int j = 1; j < 7; ++j)
        for (int i = i0; i < i0 + w && i < 11; ++i) v.labels[std::size_t(i + 12 * (j + 8 * k))] = label;
    i0 += w;
  }
  return v;
}

}  // namespace

TEST(CtImportNifti, LabelMapWithSidecarTable) {
  TempDir d;
  writeNifti(boxes({{3, 3}, {1, 3}, {7, 2}}), d.path("seg.nii.gz"));
  d.file("seg.txt", "1 rib_left_1\n3 sternum\n7 rib_right_1\n9 unused\n");
  ImportReport rep;
  const auto s = importSegmentation(d.path("seg.nii.gz"), {}, &rep);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].name, "rib_left_1");
  EXPECT_EQ(s[0].label, 1);
  EXPECT_EQ(s[1].name, "sternum");
  EXPECT_EQ(s[2].name, "rib_right_1");
  EXPECT_EQ(s[2].label, 7);
  for (const auto& x : s) {
    EXPECT_GT(x.mesh->fn, 0) << x.name;
    EXPECT_EQ(countComponents(*x.mesh), 1) << x.name;
  }
  ASSERT_EQ(rep.lines.size(), 3u) << "the used sidecar is not listed as skipped";
  EXPECT_NE(rep.lines[1].find("72 voxels"), std::string::npos) << rep.lines[1];  // 3 x 6 x 4
  EXPECT_NE(rep.lines[1].find("spacing 0.800 x 0.800 x 1.500 mm"), std::string::npos) << rep.lines[1];
  EXPECT_NE(rep.lines[1].find("from seg.nii.gz label 3"), std::string::npos) << rep.lines[1];
}

TEST(CtImportNifti, LabelsSidecarJson) {
  TempDir d;
  writeNifti(boxes({{1, 3}, {2, 3}}), d.path("ct.nii"));
  d.file("ct_labels.json", R"({"1": "rib_left_1", "2": "rib_left_2"})");
  const auto s = importSegmentation(d.path("ct.nii"));
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[1].name, "rib_left_2");
}

TEST(CtImportNifti, TableFromTheOption) {
  TempDir d;
  writeNifti(boxes({{1, 3}, {2, 3}}), d.path("ct.nii.gz"));
  ImportOptions opt;
  opt.labelTable = "1 costal_cartilage; 2 sternum";
  auto s = importSegmentation(d.path("ct.nii.gz"), opt);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].name, "costal_cartilage");
  opt.labelTable = d.file("table.csv", "1,a\n2,b\n");  // a file's path
  s = importSegmentation(d.path("ct.nii.gz"), opt);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[1].name, "b");
}

TEST(CtImportNifti, NoTableOrMissingLabels) {
  TempDir d;
  writeNifti(boxes({{1, 3}, {2, 3}, {4, 2}}), d.path("ct.nii.gz"));
  std::string e = errorOf([&] { importSegmentation(d.path("ct.nii.gz")); });
  EXPECT_NE(e.find("has 3 labels but no label table: give one in parameter 'Label table' (lines 'value name')"),
            std::string::npos) << e;
  ImportOptions opt;
  opt.labelTable = "1 a\n3 c\n";
  e = errorOf([&] { importSegmentation(d.path("ct.nii.gz"), opt); });
  EXPECT_NE(e.find("label values 2, 4 are in the image but not in the label table"), std::string::npos) << e;
}

TEST(CtImportNifti, MaskNamedAfterTheFile) {
  TempDir d;
  writeNifti(boxes({{1, 4}}), d.path("rib_left_3.nii.gz"));
  const auto s = importSegmentation(d.path("rib_left_3.nii.gz"));
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "rib_left_3");
  EXPECT_EQ(s[0].label, 0);
  EXPECT_NEAR(s[0].mesh->bbox.Dim()[0], 4 * 0.8, 1e-4);
}

TEST(CtImportNifti, FolderOfMasksSkipsEmptyAndSmallOnes) {
  TempDir d;
  writeNifti(boxes({{1, 4}}), d.path("rib_left_2.nii.gz"));
  writeNifti(boxes({{1, 2}}), d.path("rib_left_1.nii.gz"));
  writeNifti(boxes({}), d.path("liver.nii.gz"));
  LabelVolume tiny = boxes({});
  tiny.labels[200] = 1;
  writeNifti(tiny, d.path("kidney.nii.gz"));
  ImportOptions opt;
  opt.minVoxels = 5;
  ImportReport rep;
  const auto s = importSegmentation(d.p.string(), opt, &rep);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].name, "rib_left_1");
  EXPECT_EQ(s[1].name, "rib_left_2");
  bool empty = false, small = false;
  for (const auto& l : rep.lines) {
    empty |= l.find("liver.nii.gz: no labelled voxel") != std::string::npos;
    small |= l.find("kidney") != std::string::npos && l.find("1 voxel, fewer than 5, skipped") != std::string::npos;
  }
  EXPECT_TRUE(empty);
  EXPECT_TRUE(small);
  // nothing left: an error that says why
  writeNifti(boxes({}), d.path("only_empty.nii"));
  const std::string e = errorOf([&] { importSegmentation(d.path("only_empty.nii")); });
  EXPECT_NE(e.find("nothing to import"), std::string::npos) << e;
  EXPECT_NE(e.find("no labelled voxel"), std::string::npos) << e;
}

TEST(CtImportNifti, MeshesAndLabelMapsInOneFolder) {
  TempDir d;
  writeNifti(boxes({{1, 3}}), d.path("b_rib.nii.gz"));
  d.file("a_sternum.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
  const auto s = importSegmentation(d.p.string());
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].name, "a_sternum");
  EXPECT_EQ(s[0].mesh->fn, 4);
  EXPECT_EQ(s[1].name, "b_rib");
}
