// Every shipped deformation file, and every input of the committed fuzz corpora, reads to the
// very modes (bit for bit) that the reader gave before 2D and 3D files shared one grammar
// (issue 45, item 8). The expected text is tests/reference/deformation_modes.txt; its header
// says how it was produced. Suites are named io* so that `ctest -R io` runs them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "wobble/body/lattice.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "support/source_paths.h"

namespace wobble::formats {
namespace {

namespace fs = std::filesystem;

const std::string kSource = wobble::test_env::DataDir() + "/..";
const std::string kReference = kSource + "/tests/reference/deformation_modes.txt";

// %.17g round-trips every double, so equal text means equal bits (and -0 prints as "-0").
std::string Exact(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

// FNV-1a over the text of a mode list: a short stand-in for the corpora's many inputs.
std::string Digest(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  char buffer[20];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(h));
  return buffer;
}

template <int Dim> std::string Describe(const std::vector<DeformationModeN<Dim>>& modes) {
  std::ostringstream out;
  for (const DeformationModeN<Dim>& m : modes) {
    // the source is "FILE:LINE"; only the line is independent of the checkout's folder
    out << "mode " << m.name << " size";
    for (int n : m.lattice_size) out << " " << n;
    out << " stiffness " << Exact(m.stiffness) << " damping " << Exact(m.damping) << " active " << m.active
        << " line " << m.source.substr(m.source.rfind(':') + 1) << "\n";
    for (const auto& d : m.displacement) {
      for (int a = 0; a < Dim; ++a) out << (a ? " " : "") << Exact(d[a]);
      out << "\n";
    }
  }
  return out.str();
}

// A lattice that is neither axis-aligned nor cubic, so that the 3D generators' use of the
// axes, their lengths and the sizes all show in the reference.
const LatticeN<3>& SkewLattice3() {
  static const LatticeN<3> lattice(Eigen::Vector3d(-10, 5, 2),
                                {Eigen::Vector3d(200, 30, 0), Eigen::Vector3d(-20, 150, 10), Eigen::Vector3d(5, 0, 90)},
                                {5, 4, 3}, BasisKind::kBernstein);
  return lattice;
}

std::vector<std::string> Sorted(const fs::path& folder, const std::vector<std::string>& extensions) {
  std::vector<std::string> out;
  for (const fs::directory_entry& e : fs::directory_iterator(folder)) {
    if (!e.is_regular_file()) continue;
    const std::string name = e.path().filename().string();
    for (const std::string& ext : extensions)
      if ((ext.empty() && e.path().extension().empty() && name.rfind("def_", 0) == 0) ||
          (!ext.empty() && e.path().extension() == ext))
        out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

template <class F> std::string Outcome(F&& parse) {
  try {
    return "ok " + parse();
  } catch (const ParseError& e) {
    return "error line " + std::to_string(e.line());
  }
}

// The corpus inputs of a folder, sorted.
std::vector<std::string> CorpusNames(const std::string& folder) {
  std::vector<std::string> out;
  for (const fs::directory_entry& e : fs::directory_iterator(kSource + "/fuzz/corpus/" + folder))
    out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// The reference text as the reader in this build produces it, for the given inputs (those of
// the reference: files and seeds added since are checked elsewhere, in io_test and fuzz_replay_*).
struct Names {
  std::vector<std::string> files2, files3, corpus2, corpus3;  // files relative to the checkout
};

// The inputs as they are now in the checkout (to write a reference).
Names InCheckout() {
  Names n;
  for (const std::string& folder : {std::string("data"), std::string("tests/cli")})
    for (const std::string& name : Sorted(kSource + "/" + folder, {".def", ""})) n.files2.push_back(folder + "/" + name);
  for (const std::string& name : Sorted(kSource + "/data", {".def3"})) n.files3.push_back("data/" + name);
  n.corpus2 = CorpusNames("deformation");
  n.corpus3 = CorpusNames("deformation3");
  return n;
}

std::string Current(const Names& names) {
  std::ostringstream out;
  const LatticeN<3>& table3 = ReadObjectFile<3>(kSource + "/data/table3.obj").lattice;
  // shipped 2D files: data/*.def, data/def_* and the command-line tests' files, in full
  for (const std::string& file : names.files2)
    out << "file2 " << file << "\n" << Describe(ReadDeformationFile(kSource + "/" + file));
  // shipped 3D files in full over the 3D table's lattice, and as digests over a skew one
  for (const std::string& file : names.files3) {
    const std::string path = kSource + "/" + file;
    out << "file3 " << file << " table3\n" << Describe(ReadDeformationFile(path, table3));
    out << "file3 " << file << " skew " << Digest(Describe(ReadDeformationFile(path, SkewLattice3()))) << "\n";
  }
  // the fuzz corpora: hostile inputs read the same way (same modes or an error on the same line)
  for (const std::string& name : names.corpus2) {
    const std::string path = kSource + "/fuzz/corpus/deformation/" + name;
    out << "corpus2 " << name << " "
        << Outcome([&] { return Digest(Describe(ReadDeformationFile(path))); }) << "\n";
  }
  for (const std::string& name : names.corpus3) {
    const std::string path = kSource + "/fuzz/corpus/deformation3/" + name;
    out << "corpus3 " << name << " "
        << Outcome([&] { return Digest(Describe(ReadDeformationFile(path, table3))); }) << "\n";
  }
  return out.str();
}

// The only intended changes. The 3D reader used to check a 'mode' header's name before the
// mode it ends; the one parser checks the ended mode first, as the 2D reader did, so that an
// empty mode followed by a repeated name is reported on the earlier line.
const std::vector<std::pair<std::string, std::string>> kChanged = {
    {"corpus3 12f9f0ca8b7dcb32c94698ddda8496733c0f8a68 error line 3",
     "corpus3 12f9f0ca8b7dcb32c94698ddda8496733c0f8a68 error line 2"},
    {"corpus3 7d9e859c3f7f6d0a5f13e68e5bee6e24d6a83151 error line 13",
     "corpus3 7d9e859c3f7f6d0a5f13e68e5bee6e24d6a83151 error line 12"},
};

// Lines of the reference, without its '#' header.
std::vector<std::string> Lines(std::istream& in) {
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);)
    if (line.empty() || line[0] != '#') out.push_back(line);
  return out;
}

TEST(ioDeformationReference, EveryShippedFileAndCorpusInputReadsAsBefore) {
  if (const char* write = std::getenv("WOBBLE_WRITE_DEFORMATION_REFERENCE")) {
    // the header is added by hand (see the reference file)
    std::ofstream(write) << Current(InCheckout());
    GTEST_SKIP() << "wrote " << write;
  }
  std::ifstream file(kReference);
  ASSERT_TRUE(file) << "cannot open " << kReference;
  std::vector<std::string> expected = Lines(file);
  for (const auto& [before, after] : kChanged) {
    const auto it = std::find(expected.begin(), expected.end(), before);
    ASSERT_NE(it, expected.end()) << before;
    *it = after;
  }
  Names names;
  for (const std::string& line : expected) {
    if (line.find(' ') == std::string::npos) continue;
    const std::string word = line.substr(0, line.find(' ')), rest = line.substr(word.size() + 1);
    const std::string name = rest.substr(0, rest.find(' '));
    if (word == "file2") names.files2.push_back(name);
    if (word == "file3" && rest.find(" table3") != std::string::npos) names.files3.push_back(name);
    if (word == "corpus2") names.corpus2.push_back(name);
    if (word == "corpus3") names.corpus3.push_back(name);
  }
  // the reference is not cut short: every shipped file of a29e55e, and the corpora
  ASSERT_EQ(names.files2.size(), 11u);
  ASSERT_EQ(names.files3.size(), 3u);
  ASSERT_GT(names.corpus2.size(), 50u);
  ASSERT_GT(names.corpus3.size(), 300u);
  std::istringstream in(Current(names));
  const std::vector<std::string> got = Lines(in);
  std::string where;
  for (size_t i = 0; i < std::min(expected.size(), got.size()); ++i) {
    if (expected[i].rfind("file", 0) == 0 || expected[i].rfind("corpus", 0) == 0) where = expected[i];
    ASSERT_EQ(got[i], expected[i]) << "line " << i + 1 << " of the reference (not counting its header), in " << where;
  }
  EXPECT_EQ(got.size(), expected.size());
}

// Matrix modes do not depend on the lattice: read with the body's lattice (as the command line
// and scripts now read them) every shipped 2D file and 2D corpus input gives the same result.
TEST(ioDeformationReference, TwoDFilesReadTheSameWithTheBodysLattice) {
  const Lattice table = ReadObjectFile(kSource + "/data/table.obj").lattice;
  std::vector<std::string> paths;
  for (const std::string& name : Sorted(kSource + "/data", {".def", ""})) paths.push_back(kSource + "/data/" + name);
  for (const std::string& name : CorpusNames("deformation"))
    paths.push_back(kSource + "/fuzz/corpus/deformation/" + name);
  int same = 0;
  for (const std::string& path : paths) {
    const std::string without = Outcome([&] { return Describe(ReadDeformationFile(path)); });
    if (without.rfind("ok", 0) != 0) continue;  // refused inputs may now hold generators
    EXPECT_EQ(Outcome([&] { return Describe(ReadDeformationFile(path, table)); }), without) << path;
    ++same;
  }
  EXPECT_GE(same, 19);  // the 10 data/ files and the 9 corpus inputs the reader accepted at a29e55e
}

}  // namespace
}  // namespace wobble::formats
