// Dataset 2412 (elements) decoded from the verbatim copy the reader keeps: a hand-written block
// with every kind of record, the shared files that hold 2412, a malformed block, and `ema info`.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "ema/core/error.hpp"
#include "ema/formats/info.hpp"
#include "ema/formats/uff.hpp"

namespace ema::formats::uff {
namespace {

namespace fs = std::filesystem;

fs::path Data(const std::string& rel) { return fs::path(EMA_REAL_DATA_DIR) / "uff" / rel; }

fs::path WriteText(const std::string& name, const std::string& text) {
  fs::create_directories(EMA_TEST_TMP_DIR);
  const fs::path p = fs::path(EMA_TEST_TMP_DIR) / (name + "-" + std::to_string(getpid()) + ".unv");
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

// The 2412 dataset of a file, decoded.
Elements2412 ElementsOf(const fs::path& path) {
  for (const Dataset& d : ReadFile(path))
    if (const auto* raw = std::get_if<RawDataset>(&d.body); raw && d.number == 2412)
      return DecodeElements2412(*raw, path.string(), d.line);
  ADD_FAILURE() << "no dataset 2412 in " << path;
  return {};
}

// A quadrilateral, a linear beam (with its beam record), a 10-node tetrahedron (node labels on
// two lines, 8 + 2) and a triangle with 10-digit labels whose full I10 fields touch.
const char* kBlock =
    "    -1\n"
    "  2412\n"
    "         1        44         2         3         7         4\n"
    "        11        12        13        14\n"
    "         2        21         5         0         1         2\n"
    "        99         4         6\n"
    "        11        12\n"
    "         3       118         1         1         8        10\n"
    "         1         2         3         4         5         6         7         8\n"
    "         9        10\n"
    "1234567890        91         1         1         8         3\n"
    "10000000011000000002        23\n"
    "    -1\n";

TEST(Uff2412, HandWrittenBlockEveryField) {
  const fs::path path = WriteText("elements", kBlock);
  const Elements2412 e = ElementsOf(path);
  ASSERT_EQ(e.elements.size(), 4u);
  const Element2412& quad = e.elements[0];
  EXPECT_EQ(quad.label, 1);
  EXPECT_EQ(quad.fe_descriptor, 44);
  EXPECT_EQ(quad.physical_property, 2);
  EXPECT_EQ(quad.material_property, 3);
  EXPECT_EQ(quad.colour, 7);
  EXPECT_EQ(quad.nodes, (std::vector<std::int64_t>{11, 12, 13, 14}));
  EXPECT_EQ(quad.beam_orientation_node, 0);
  const Element2412& beam = e.elements[1];
  EXPECT_EQ(beam.fe_descriptor, 21);
  EXPECT_EQ(beam.beam_orientation_node, 99);
  EXPECT_EQ(beam.beam_fore_cross_section, 4);
  EXPECT_EQ(beam.beam_aft_cross_section, 6);
  EXPECT_EQ(beam.nodes, (std::vector<std::int64_t>{11, 12}));
  const Element2412& tetra = e.elements[2];
  EXPECT_EQ(tetra.fe_descriptor, 118);
  EXPECT_EQ(tetra.nodes, (std::vector<std::int64_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  const Element2412& tri = e.elements[3];
  EXPECT_EQ(tri.label, 1234567890);
  EXPECT_EQ(tri.fe_descriptor, 91);
  EXPECT_EQ(tri.nodes, (std::vector<std::int64_t>{1000000001, 1000000002, 23}));
}

TEST(Uff2412, WrittenBackByteForByteAndDecodesTheSame) {
  const fs::path in = WriteText("elements_in", kBlock);
  const fs::path out = fs::path(EMA_TEST_TMP_DIR) / ("elements_out-" + std::to_string(getpid()) + ".unv");
  WriteFile(out, ReadFile(in));
  std::ifstream a(in, std::ios::binary), b(out, std::ios::binary);
  std::stringstream sa, sb;
  sa << a.rdbuf();
  sb << b.rdbuf();
  EXPECT_EQ(sb.str(), sa.str());
  EXPECT_EQ(ElementsOf(out).elements.size(), 4u);
}

TEST(Uff2412, SharedFilesDecode) {
  // Counts and records checked against the files (awk over their 2412 blocks).
  const Elements2412 mixed = ElementsOf(Data("pyuff/mesh_test_uff2412_mixed.uff"));
  ASSERT_EQ(mixed.elements.size(), 5u);
  EXPECT_EQ(mixed.elements[0].fe_descriptor, 44);
  EXPECT_EQ(mixed.elements[0].nodes, (std::vector<std::int64_t>{3, 4, 5, 6}));
  EXPECT_EQ(mixed.elements[1].fe_descriptor, 41);
  EXPECT_EQ(mixed.elements[1].nodes, (std::vector<std::int64_t>{3, 4, 11}));

  // NX: 17 rods, each with a beam record "0 0 0".
  const Elements2412 nx = ElementsOf(Data("pyuff/NX simulation output.uff"));
  ASSERT_EQ(nx.elements.size(), 17u);
  EXPECT_EQ(nx.elements[0].fe_descriptor, 11);
  EXPECT_EQ(nx.elements[0].colour, 6);
  EXPECT_EQ(nx.elements[0].nodes, (std::vector<std::int64_t>{3992, 9678}));

  // Simcenter: 16688 elements, 4751 linear beams among shells; element 12082 is a beam.
  const Elements2412 sim = ElementsOf(Data("pyuff/simcenter_exported_result.uff"));
  ASSERT_EQ(sim.elements.size(), 16688u);
  std::map<int, int> by_descriptor;
  const Element2412* e12082 = nullptr;
  for (const auto& e : sim.elements) {
    ++by_descriptor[e.fe_descriptor];
    if (e.label == 12082) e12082 = &e;
  }
  EXPECT_EQ(by_descriptor, (std::map<int, int>{{21, 4751}, {91, 21}, {94, 11916}}));
  ASSERT_NE(e12082, nullptr);
  EXPECT_EQ(e12082->physical_property, 23);
  EXPECT_EQ(e12082->beam_orientation_node, 0);
  EXPECT_EQ(e12082->beam_fore_cross_section, 1);
  EXPECT_EQ(e12082->beam_aft_cross_section, 1);
  EXPECT_EQ(e12082->nodes, (std::vector<std::int64_t>{1894, 1443}));

  EXPECT_EQ(ElementsOf(Data("ufffiles-jl/dataset2412.unv")).elements.size(), 267u);
}

TEST(Uff2412, NodeListEndingEarlyNamesFileLineAndElement) {
  // Element 7 announces 4 nodes; its one line holds 3.
  const fs::path path = WriteText("elements_short",
                                  "    -1\n  2412\n         7        44         0         0         1         4\n"
                                  "         1         2         3\n    -1\n");
  try {
    ElementsOf(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string() + ":4"), std::string::npos) << what;
    EXPECT_NE(what.find("dataset 2412 element 7"), std::string::npos) << what;
    EXPECT_NE(what.find("expected 4"), std::string::npos) << what;
  }
}

TEST(Uff2412, InfoCountsTheElements) {
  const formats::FileSummary s = formats::SummarizeFile(Data("pyuff/mesh_test_uff2412_mixed.uff"));
  EXPECT_EQ(s.elements, 5);
  EXPECT_EQ(s.element_descriptors, (std::map<int, std::int64_t>{{41, 4}, {44, 1}}));
  EXPECT_NE(formats::SummaryText(s).find("elements: 5 (FE descriptor 41 x4 44 x1)"), std::string::npos);
  ASSERT_TRUE(fs::exists(EMA_EXECUTABLE));
  const fs::path out = fs::path(EMA_TEST_TMP_DIR) / ("info2412-" + std::to_string(getpid()) + ".txt");
  const std::string cmd = std::string("'") + EMA_EXECUTABLE + "' info '" +
                          Data("pyuff/mesh_test_uff2412_mixed.uff").string() + "' >'" + out.string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("elements: 5 (FE descriptor 41 x4 44 x1)"), std::string::npos) << text.str();
}

}  // namespace
}  // namespace ema::formats::uff
