// Correlate(): DOF matching, pairing, table rows and remarks, COMAC, bad input; a UFF 55 file
// written by another tool read as model modes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "ema/core/error.hpp"
#include "ema/correlation/correlate.hpp"
#include "ema/formats/io.hpp"

namespace ema::correlation {
namespace {

using cd = std::complex<double>;

// A model set: nodes 1..4, +X +Y +Z, 3 modes with distinct random shapes.
ModeSet MakeModel() {
  ModeSet m;
  m.source = "model";
  for (int node = 1; node <= 4; ++node)
    for (int dir = 1; dir <= 3; ++dir) m.dofs.push_back({node, dir});
  std::mt19937 rng(1);
  std::normal_distribution<double> g;
  const double f[] = {100.0, 150.0, 230.0};
  for (double fm : f) {
    Mode mode;
    mode.frequency_hz = fm;
    mode.shape.resize(12);
    for (int i = 0; i < 12; ++i) mode.shape(i) = g(rng);
    m.modes.push_back(mode);
  }
  return m;
}

TEST(Correlate, PairsAgreementRemarksAndComac) {
  const ModeSet model = MakeModel();
  ModeSet test;
  test.source = "test";
  // Test DOFs in another order, one measured along -Y (sign flip), one node the model lacks.
  std::vector<std::pair<int, double>> map;  // model index, sign
  for (int node = 4; node >= 1; --node)
    for (int dir = 1; dir <= 3; ++dir) {
      const int code = (node == 2 && dir == 2) ? -2 : dir;
      test.dofs.push_back({node, code});
      map.push_back({(node - 1) * 3 + dir - 1, code < 0 ? -1.0 : 1.0});
    }
  test.dofs.push_back({99, 3});
  // Test modes: model modes 1 and 2 swapped in order, complex-scaled; model mode 3 missing.
  const int order[] = {1, 0};
  const double f_test[] = {160.0, 95.0};
  const double damping[] = {0.02, 0.004};
  for (int t = 0; t < 2; ++t) {
    Mode mode;
    mode.frequency_hz = f_test[t];
    mode.damping_ratio = damping[t];
    mode.shape.resize(13);
    for (int i = 0; i < 12; ++i)
      mode.shape(i) = cd(0.0, 3.0) * map[i].second * model.modes[order[t]].shape(map[i].first);
    mode.shape(12) = 1.0;  // node 99: not in the model, must not enter the MAC
    test.modes.push_back(mode);
  }
  const CorrelationResult r = Correlate(test, model);
  EXPECT_EQ(r.shared_dof_count, 12);
  EXPECT_EQ(r.test_dof_count, 13);
  ASSERT_EQ(r.pairing.pairs.size(), 2u);
  for (const ModePair& p : r.pairing.pairs) {
    EXPECT_EQ(p.model, order[p.test]);
    EXPECT_NEAR(p.mac, 1.0, 1e-12);  // same vector up to a complex factor and the sign flip
  }
  EXPECT_EQ(r.pairing.unpaired_model, std::vector<int>{2});
  // Rows in model order: mode 1 (test 95 Hz), mode 2 (test 160 Hz), mode 3 model-only.
  ASSERT_EQ(r.rows.size(), 3u);
  EXPECT_NEAR(r.rows[0].agreement_pct, 95.0, 1e-12);                  // 100 (1 − 5/100)
  EXPECT_NEAR(r.rows[1].agreement_pct, 100.0 * (1 - 10.0 / 150.0), 1e-12);
  EXPECT_NEAR(r.rows[0].frequency_error_pct, 100.0 * 5.0 / 95.0, 1e-12);
  EXPECT_EQ(r.rows[0].remark, "paired");
  EXPECT_EQ(r.rows[1].remark, "paired; interface-dominated");  // test damping 2 % > 1 %
  EXPECT_EQ(r.rows[2].remark, "model-only");
  EXPECT_NEAR(r.min_agreement_pct, 100.0 * (1 - 10.0 / 150.0), 1e-12);
  EXPECT_NEAR(r.mean_mac, 1.0, 1e-12);
  // Identical shapes: every COMAC is 1.
  for (const ComacEntry& c : r.comac) EXPECT_NEAR(c.comac, 1.0, 1e-12);

  // Tables carry the numbers and the remarks.
  const std::string md = FormatCorrelationTable(r, TableFormat::kMarkdown);
  EXPECT_NE(md.find("| 95.0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("model-only"), std::string::npos);
  EXPECT_NE(md.find("Shared DOFs: 12 of 13"), std::string::npos);
  const std::string csv = FormatCorrelationTable(r, TableFormat::kCsv);
  // No MPC/MPD/MCF on these test modes: empty cells.
  EXPECT_NE(csv.find("1,100.0,95.0,0.40,95.0,5.3,1.000,,,,\"paired\""), std::string::npos) << csv;
  const std::string html = FormatCorrelationTable(r, TableFormat::kHtml);
  EXPECT_NE(html.find("<td>paired; interface-dominated</td>"), std::string::npos) << html;
  EXPECT_NE(html.find("<table>"), std::string::npos);
}

TEST(Correlate, TestModeComplexityWrittenReadAndTabulated) {
  // Test mode 1 made complex on purpose: phi = [1, e^{j30°}] has MPC 0.75, MPD 15°, MCF 0.25
  // (closed form; tests/curvefit/complexity_test.cpp computes them from the shape). Test mode 2
  // is real: MPC 1, MPD 0, MCF 0. Written as UFF 55, read back, correlated, tabulated.
  ModeSet model, test;
  model.source = "model";
  model.dofs = test.dofs = {{1, 3}, {2, 3}};
  const double f[] = {100.0, 180.0};
  const cd shapes_test[2][2] = {{1.0, std::polar(1.0, M_PI / 6.0)}, {1.0, -1.0}};
  const cd shapes_model[2][2] = {{1.0, 1.0}, {1.0, -1.0}};
  const double mpc[] = {0.75, 1.0}, mpd[] = {15.0, 0.0}, mcf[] = {0.25, 0.0};
  for (int k = 0; k < 2; ++k) {
    Mode m;
    m.frequency_hz = f[k];
    m.damping_ratio = 0.005;
    m.pole = FrequencyAndDampingToPole(m.frequency_hz, m.damping_ratio);
    m.shape = Eigen::VectorXcd(2);
    m.shape << shapes_test[k][0], shapes_test[k][1];
    m.mpc = mpc[k];
    m.mpd = mpd[k];
    m.mcf = mcf[k];
    test.modes.push_back(m);
    Mode mm;
    mm.frequency_hz = f[k] * 1.02;
    mm.shape = Eigen::VectorXcd(2);
    mm.shape << shapes_model[k][0], shapes_model[k][1];
    model.modes.push_back(mm);
  }
  const std::filesystem::path dir = std::filesystem::path(EMA_TEST_TMP_DIR);
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / ("complex_test_modes-" + std::to_string(getpid()) + ".unv");
  formats::WriteModeSet(file, test);
  const ModeSet read = formats::ReadModeSet(file);
  ASSERT_EQ(read.modes.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    // Written with 7 significant digits (1P E13.6): 1e-6 relative, plus 1e-12 for the zeros.
    EXPECT_NEAR(read.modes[k].mpc, mpc[k], 1e-6 * mpc[k] + 1e-12) << k;
    EXPECT_NEAR(read.modes[k].mpd, mpd[k], 1e-6 * mpd[k] + 1e-12) << k;
    EXPECT_NEAR(read.modes[k].mcf, mcf[k], 1e-6 * mcf[k] + 1e-12) << k;
  }
  const CorrelationResult r = Correlate(read, model);
  ASSERT_EQ(r.rows.size(), 2u);
  ASSERT_TRUE(r.rows[0].paired());
  EXPECT_EQ(r.rows[0].test_mode, 0);
  EXPECT_NEAR(r.rows[0].test_mpc, 0.75, 1e-6);
  EXPECT_NEAR(r.rows[0].test_mpd_deg, 15.0, 1e-5);
  EXPECT_NEAR(r.rows[0].test_mcf, 0.25, 1e-6);
  EXPECT_NEAR(r.rows[1].test_mpc, 1.0, 1e-6);

  const std::string csv = FormatCorrelationTable(r, TableFormat::kCsv);
  EXPECT_NE(csv.find(",mac,test_mpc,test_mpd_deg,test_mcf,remark\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",0.750,15.0,0.250,\"paired\""), std::string::npos) << csv;
  EXPECT_NE(csv.find(",1.000,0.0,0.000,\"paired\""), std::string::npos) << csv;
  const std::string md = FormatCorrelationTable(r, TableFormat::kMarkdown);
  EXPECT_NE(md.find("| MAC | MPC | MPD [°] | MCF | Remark |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 0.750 | 15.0 | 0.250 | paired |"), std::string::npos) << md;
  const std::string html = FormatCorrelationTable(r, TableFormat::kHtml);
  EXPECT_NE(html.find("<td>0.750</td><td>15.0</td><td>0.250</td>"), std::string::npos) << html;
}

TEST(Correlate, ComacPointsAtTheBadDof) {
  const ModeSet model = MakeModel();
  ModeSet test = model;
  test.source = "test";
  std::mt19937 rng(4);
  std::normal_distribution<double> g;
  for (Mode& m : test.modes) m.shape(7) += 2.0 * g(rng) * m.shape.norm() / std::sqrt(12.0);  // node 3 +Y
  const CorrelationResult r = Correlate(test, model);
  ASSERT_FALSE(r.comac.empty());
  EXPECT_EQ(r.comac.front().dof, (Dof{3, 2}));  // worst first
}

TEST(Correlate, NearestNodeWithinTolerance) {
  ModeSet model = MakeModel();
  for (int node = 1; node <= 4; ++node) model.geometry.push_back({node, Eigen::Vector3d(0.1 * node, 0, 0)});
  ModeSet test = model;
  test.source = "test";
  test.geometry.clear();
  for (Dof& d : test.dofs) d.node += 100;  // other numbering
  for (int node = 1; node <= 4; ++node) test.geometry.push_back({node + 100, Eigen::Vector3d(0.1 * node + 0.002, 0, 0)});
  EXPECT_THROW(Correlate(test, model), InputError);  // by id nothing is shared
  CorrelationOptions options;
  options.dofs.tolerance_m = 0.005;  // 2 mm off, 5 mm tolerance
  const CorrelationResult r = Correlate(test, model, options);
  EXPECT_EQ(r.shared_dof_count, 12);
  EXPECT_EQ(r.dof_match.nodes_by_distance, 4);
  EXPECT_EQ(r.pairing.pairs.size(), 3u);
  options.dofs.tolerance_m = 0.001;  // too tight
  EXPECT_THROW(Correlate(test, model, options), InputError);
}

TEST(Correlate, RotatedMeasurementFrameIsProjected) {
  const ModeSet model = MakeModel();
  // Node 1 measured in a frame rotated 90° about Z: local X = global Y, local Y = −global X.
  ModeSet test = model;
  test.source = "test";
  Eigen::Matrix3d frame;
  frame << 0, -1, 0,  //
      1, 0, 0,        //
      0, 0, 1;
  for (Mode& m : test.modes) {
    const cd ux = m.shape(0), uy = m.shape(1);
    m.shape(0) = uy;   // local X reads global Y
    m.shape(1) = -ux;  // local Y reads −global X
  }
  EXPECT_LT(Correlate(test, model).mean_mac, 0.999);  // unprojected: shapes disagree
  CorrelationOptions options;
  options.dofs.test_frames[1] = frame;
  EXPECT_NEAR(Correlate(test, model, options).mean_mac, 1.0, 1e-12);
}

TEST(Correlate, BadInput) {
  const ModeSet model = MakeModel();
  ModeSet empty = model;
  empty.modes.clear();
  empty.source = "empty.unv";
  try {
    Correlate(empty, model);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.unv: no modes"), std::string::npos) << e.what();
  }
  ModeSet foreign = model;
  foreign.source = "foreign.unv";
  for (Dof& d : foreign.dofs) d.node += 50;
  try {
    Correlate(foreign, model);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no DOF shared"), std::string::npos) << e.what();
  }
  ModeSet ragged = model;
  ragged.modes[1].shape.resize(5);
  EXPECT_THROW(Correlate(ragged, model), InputError);
}

TEST(Correlate, Uff55FromAnotherToolAsModelModes) {
  // pyuff's uff55_translation.uff: 3 real modes (10, 12, 13 Hz) at nodes 1..4, X Y Z.
  const ModeSet model = formats::ReadModeSet(std::string(EMA_REAL_DATA_DIR) + "/uff/pyuff/uff55_translation.uff");
  ASSERT_EQ(model.modes.size(), 3u);
  EXPECT_EQ(model.dofs.size(), 12u);
  EXPECT_NEAR(model.modes[0].frequency_hz, 10.0, 1e-9);
  EXPECT_NEAR(model.modes[2].frequency_hz, 13.0, 1e-9);
  // The "test": the same shapes, order reversed, complex scaled, frequencies 2 % high, 1 %
  // noise on the shapes (fixed seed). Pairing must undo the order; agreement = 98 %.
  ModeSet test;
  test.source = "synthetic test";
  test.dofs = model.dofs;
  std::mt19937 rng(8);
  std::normal_distribution<double> g;
  for (int t = 0; t < 3; ++t) {
    Mode m = model.modes[2 - t];
    m.frequency_hz *= 1.02;
    const double rms = m.shape.norm() / std::sqrt(static_cast<double>(m.shape.size()));
    m.shape *= cd(-1.0, 0.5);
    for (Eigen::Index i = 0; i < m.shape.size(); ++i) m.shape(i) += 0.01 * rms * cd(g(rng), g(rng));
    test.modes.push_back(m);
  }
  const CorrelationResult r = Correlate(test, model);
  ASSERT_EQ(r.pairing.pairs.size(), 3u);
  for (const ModePair& p : r.pairing.pairs) {
    EXPECT_EQ(p.model, 2 - p.test);
    EXPECT_GT(p.mac, 0.99);  // 1 % noise costs about 1e-4 of MAC
  }
  for (const CorrelationRow& row : r.rows) EXPECT_NEAR(row.agreement_pct, 98.0, 1e-9);
}

}  // namespace
}  // namespace ema::correlation
