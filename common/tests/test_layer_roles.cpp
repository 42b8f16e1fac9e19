// Layer roles (pectus/layer_roles.h): a landmark layer by its contents and by where it lies, a before layer by
// its mesh; the named layer first, else the one layer with the role, else a refusal naming the candidates.
#include <gtest/gtest.h>

#include <vcg/complex/algorithms/create/platonic.h>

#include "pectus/errors.h"
#include "pectus/labels.h"
#include "pectus/layer_roles.h"

namespace {

using pectus::LayerRef;

/// a point layer of landmarks on the box [-1, 1]^3 moved by dx along x: joints 101 and 201 and 500 at its corners
void landmarks(CMeshO& m, double dx) {
  pectus::writeLandmarks(m, {{101, {dx - 1, -1, -1}}, {201, {dx + 1, 1, 1}}, {500, {dx - 1, 1, -1}}, {700, {dx, 0, 0}}});
}

struct Doc {
  CMeshO cage, moved, box, cageLms, movedLms, cloud;
  std::vector<LayerRef> layers;
  Doc() {
    vcg::tri::Box<CMeshO>(cage, vcg::Box3<Scalarm>(Point3m(-1, -1, -1), Point3m(1, 1, 1)));
    vcg::tri::Box<CMeshO>(moved, vcg::Box3<Scalarm>(Point3m(-1, -1, -1), Point3m(1, 1, 1)));
    for (auto& v : moved.vert) v.P()[0] += 40;  // the deformed copy: 40 mm away
    vcg::tri::Tetrahedron<CMeshO>(box);  // another mesh (4 vertices)
    landmarks(cageLms, 0);
    landmarks(movedLms, 40);
    pectus::writeLandmarks(cloud, {{0, {0, 0, 0}}, {3, {1, 0, 0}}});
    layers = {{"box", &box, 0}, {"cage", &cage, 1}, {"cage landmarks", &cageLms, 2}, {"result", &moved, 3},
              {"result landmarks", &movedLms, 4}, {"cloud", &cloud, 5}};
  }
};

TEST(LayerRoles, LandmarkLayerByContents) {
  Doc d;
  EXPECT_EQ(pectus::landmarkLayerProblem(d.cageLms, {500, 700}), "");
  EXPECT_NE(pectus::landmarkLayerProblem(d.cageLms, {501}).find("no landmark 501"), std::string::npos);
  EXPECT_NE(pectus::landmarkLayerProblem(d.cage, {}).find("not a landmark layer"), std::string::npos);
  EXPECT_NE(pectus::landmarkLayerProblem(d.cloud, {}).find("not a landmark layer"), std::string::npos);
  EXPECT_TRUE(pectus::isLandmarkCode(212) && pectus::isLandmarkCode(625) && pectus::isLandmarkCode(701));
  EXPECT_FALSE(pectus::isLandmarkCode(0) || pectus::isLandmarkCode(300) || pectus::isLandmarkCode(600));
}

TEST(LayerRoles, NamedLandmarkLayerWhenItFits) {
  Doc d;
  const auto c = pectus::chooseLandmarkLayer(d.layers, 2, {1}, {&d.cage}, {500}, "landmarkLayer", "");
  EXPECT_EQ(c.index, 2);
  EXPECT_EQ(c.note, "");
}

TEST(LayerRoles, LandmarkLayerOfTheCageWhenTheNamedOneIsNone) {
  Doc d;
  // the script's number names the cage (a layer was loaded first): the landmarks lying on the cage are taken
  auto c = pectus::chooseLandmarkLayer(d.layers, 1, {1}, {&d.cage}, {500}, "landmarkLayer", "");
  EXPECT_EQ(c.index, 2);
  EXPECT_NE(c.note.find("names layer 1 'cage', which is the cage itself"), std::string::npos) << c.note;
  // for the deformed copy, the landmarks moved with it
  c = pectus::chooseLandmarkLayer(d.layers, 0, {3}, {&d.moved}, {500}, "landmarkLayer", "");
  EXPECT_EQ(c.index, 4);
  // a landmark layer of the other cage, named: the one lying on this cage is taken instead
  c = pectus::chooseLandmarkLayer(d.layers, 4, {1}, {&d.cage}, {500}, "landmarkLayer", "");
  EXPECT_EQ(c.index, 2);
  EXPECT_NE(c.note.find("mm from the cage"), std::string::npos) << c.note;
}

TEST(LayerRoles, LandmarkLayerRefusals) {
  Doc d;
  // no cage to place them on: two candidates, none clearly the one
  try {
    pectus::chooseLandmarkLayer(d.layers, 0, {}, {}, {}, "landmarkLayer", "Pick one.");
    FAIL();
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("layer 2 'cage landmarks' and layer 4 'result landmarks'"), std::string::npos) << e.what();
  }
  // a code none has
  try {
    pectus::chooseLandmarkLayer(d.layers, 1, {1}, {&d.cage}, {501}, "landmarkLayer", "Pick one.");
    FAIL();
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no landmark layer with landmark 501"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Pick one."), std::string::npos) << e.what();
  }
}

TEST(LayerRoles, BeforeLayer) {
  Doc d;
  auto c = pectus::chooseBeforeLayer(d.layers, 1, 3, -1, "beforeLayer");
  EXPECT_EQ(c.index, 1);
  EXPECT_EQ(c.note, "");
  c = pectus::chooseBeforeLayer(d.layers, 0, 3, -1, "beforeLayer");  // the box: another mesh
  EXPECT_EQ(c.index, 1);
  EXPECT_NE(c.note.find("not the same model"), std::string::npos) << c.note;
  // two layers are the same mesh: the recorded source decides, else a refusal naming both
  std::vector<LayerRef> two = d.layers;
  CMeshO copy;
  vcg::tri::Box<CMeshO>(copy, vcg::Box3<Scalarm>(Point3m(-1, -1, -1), Point3m(1, 1, 1)));
  two.push_back({"cage copy", &copy, 6});
  EXPECT_EQ(pectus::chooseBeforeLayer(two, 0, 3, 6, "beforeLayer").index, 6);
  EXPECT_THROW(pectus::chooseBeforeLayer(two, 0, 3, -1, "beforeLayer"), pectus::InputError);
  std::vector<LayerRef> alone = {d.layers[0], d.layers[3]};
  EXPECT_THROW(pectus::chooseBeforeLayer(alone, 0, 1, -1, "beforeLayer"), pectus::InputError);
}

}  // namespace
