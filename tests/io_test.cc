// Object and deformation files: the data/ files of the thesis' bodies, the row/column
// convention of §4.10.1's matrices, and a ParseError with the right line for every kind of
// malformed input.
// Suites are named io* so that `ctest -R io` runs all of them.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <functional>
#include <memory>
#include <sstream>

#include "wobble/body/body_model.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/world/world.h"
#include "support/source_paths.h"

namespace wobble::formats {
namespace {

const std::string kData = wobble::test_env::DataDir();

// Displacement of a body-frame point under a mode: Σ_ij B_i(s) B_j(t) d_ij.
Eigen::Vector2d ModeDisplacement(const Lattice& lattice, const DeformationMode& mode, const Eigen::Vector2d& p) {
  const std::vector<double> w = lattice.Weights(lattice.LocalCoords(p));
  Eigen::Vector2d d = Eigen::Vector2d::Zero();
  for (int c = 0; c < lattice.size(); ++c) d += w[c] * mode.displacement[c];
  return d;
}

// Smallest singular value of the stacked Jacobian [e_x, e_y, S b0_k, B_k] over all mass points,
// columns scaled to unit length: > 0 iff no mode is a combination of the others and the rigid
// motions on these points (else the mass matrix M = Σ m J_kᵀ J_k would be singular).
double SmallestNormalizedSingularValue(const BodyModel& body) {
  const int n = body.num_points(), q = body.num_q();
  Eigen::MatrixXd J(2 * n, q);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d& b0 = body.rest_local(k);
    J.block(2 * k, 0, 2, 2).setIdentity();
    J(2 * k, 2) = -b0.y();
    J(2 * k + 1, 2) = b0.x();
    J.block(2 * k, kRigidDofs, 2, body.num_modes()) = body.mode_matrix(k);
  }
  for (int c = 0; c < q; ++c) J.col(c).normalize();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
  return svd.singularValues()(q - 1);
}

void ExpectParseError(const std::function<void()>& parse, const std::string& file, int line,
                      const std::string& message_part) {
  try {
    parse();
    ADD_FAILURE() << "no ParseError; expected one on line " << line << " mentioning \"" << message_part << "\"";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(message_part), std::string::npos)
        << "message \"" << e.what() << "\" does not mention \"" << message_part << "\"";
    EXPECT_EQ(std::string(e.what()), file + ":" + std::to_string(line) + ": " + e.message());
  }
}

void ExpectObjectError(const std::string& text, int line, const std::string& message_part) {
  ExpectParseError(
      [&] {
        std::istringstream in(text);
        ParseObject(in, "test.obj");
      },
      "test.obj", line, message_part);
}

void ExpectModesError(const std::string& text, int line, const std::string& message_part) {
  ExpectParseError(
      [&] {
        std::istringstream in(text);
        ParseDeformations(in, "test.def");
      },
      "test.def", line, message_part);
}

std::vector<DeformationMode> Modes(const std::string& text, const std::string& name = "test.def") {
  std::istringstream in(text);
  return ParseDeformations(in, name);
}

BodyDef Object(const std::string& text, const std::string& name = "test.obj") {
  std::istringstream in(text);
  return ParseObject(in, name);
}

// ---------------------------------------------------------------- data/ files

TEST(ioDataFiles, EveryFileParsesAndFitsItsBody) {
  const BodyDef table = ReadObjectFile(kData + "/table.obj");
  for (const char* file : {"bend.def", "shear.def", "vsquash.def", "hsquash.def", "table_modes.def"}) {
    SCOPED_TRACE(file);
    EXPECT_NO_THROW(BodyModel body(table, ReadDeformationFile(kData + "/" + file)));
  }
  EXPECT_NO_THROW(BodyModel rod(ReadObjectFile(kData + "/rod.obj"), ReadDeformationFile(kData + "/rod_stretch.def")));
  EXPECT_NO_THROW(BodyModel pot(ReadObjectFile(kData + "/pot.obj"), ReadDeformationFile(kData + "/def_pot")));
}

TEST(ioDataFiles, TableOfFigure12) {
  const BodyDef table = ReadObjectFile(kData + "/table.obj");
  EXPECT_EQ(table.name, "table");
  EXPECT_EQ(table.lattice.num_s(), 4);
  EXPECT_EQ(table.lattice.num_t(), 4);
  EXPECT_EQ(table.lattice.basis(), BasisKind::kBernstein);
  EXPECT_EQ(table.lattice.origin(), Eigen::Vector2d(0, 0));
  EXPECT_EQ(table.lattice.axis_s(), Eigen::Vector2d(300, 0));
  EXPECT_EQ(table.lattice.axis_t(), Eigen::Vector2d(0, 100));
  ASSERT_EQ(table.masses.size(), 11u);
  ASSERT_EQ(table.mass_positions.size(), 11u);
  for (double m : table.masses) EXPECT_EQ(m, 50.0);
  int top = 0, left = 0, right = 0;
  for (const Eigen::Vector2d& p : table.mass_positions) {
    top += p.y() == 100;
    left += p.x() == 0 && p.y() < 100;
    right += p.x() == 300 && p.y() < 100;
  }
  EXPECT_EQ(top, 5);
  EXPECT_EQ(left, 3);
  EXPECT_EQ(right, 3);
  ASSERT_EQ(table.shapes.size(), 3u);
  for (const Polyline& p : table.shapes) {
    EXPECT_EQ(p.points.size(), 2u);
    EXPECT_FALSE(p.closed);
  }
}

TEST(ioDataFiles, BendRowsRunBottomToTopColumnsLeftToRight) {
  const std::vector<DeformationMode> modes = ReadDeformationFile(kData + "/bend.def");
  ASSERT_EQ(modes.size(), 1u);
  const DeformationMode& bend = modes[0];
  EXPECT_EQ(bend.name, "bend");
  EXPECT_EQ(bend.lattice_size[0], 4);
  EXPECT_EQ(bend.lattice_size[1], 4);
  EXPECT_EQ(bend.stiffness, 0.0);
  EXPECT_EQ(bend.damping, 0.0);
  EXPECT_FALSE(bend.active);
  const Lattice lattice;
  EXPECT_EQ(bend.displacement[lattice.Index(0, 0)], Eigen::Vector2d(150, 0));     // first number of x:, y:
  EXPECT_EQ(bend.displacement[lattice.Index(1, 3)], Eigen::Vector2d(-150, 100));  // last row, 2nd column
  EXPECT_EQ(bend.displacement[lattice.Index(3, 0)], Eigen::Vector2d(-150, 0));    // first row, last column
  EXPECT_EQ(bend.displacement[lattice.Index(0, 1)], Eigen::Vector2d(50, 0));      // second row, first column
  EXPECT_EQ(bend.displacement[1 * 4 + 3], Eigen::Vector2d(-150, 100));            // flat index i*num_t + j
}

TEST(ioDataFiles, BendAtPointTwoArchesTheTable) {
  const BodyDef table = ReadObjectFile(kData + "/table.obj");
  const DeformationMode bend = ReadDeformationFile(kData + "/bend.def")[0];
  const double gamma = 0.2;
  const Eigen::Vector2d middle(150, 100), left_end(0, 100), right_end(300, 100);
  const Eigen::Vector2d moved = middle + gamma * ModeDisplacement(table.lattice, bend, middle);
  // Σ_i B_i(1/2) d_i3,y = 100 (3/8 + 3/8) = 75, so the middle of the top rises by 15
  EXPECT_NEAR(moved.y(), 115.0, 1e-9);
  EXPECT_NEAR(moved.x(), 150.0, 1e-9);
  // the ends of the top stay at the height of the legs' tops: the top arches
  EXPECT_NEAR(ModeDisplacement(table.lattice, bend, left_end).y(), 0.0, 1e-9);
  EXPECT_NEAR(ModeDisplacement(table.lattice, bend, right_end).y(), 0.0, 1e-9);
  // and the same through BodyModel's b0 + B γ for the top's middle mass point
  const BodyModel body(table, {bend});
  for (int k = 0; k < body.num_points(); ++k)
    if (table.mass_positions[k] == middle) {
      const Eigen::Vector2d p = body.rest_local(k) + body.mode_matrix(k) * Eigen::VectorXd::Constant(1, gamma);
      EXPECT_NEAR(p.y(), 115.0, 1e-9);
    }
}

TEST(ioDataFiles, TableModesFileHoldsTheFourSingleModeFiles) {
  const std::vector<DeformationMode> modes = ReadDeformationFile(kData + "/table_modes.def");
  ASSERT_EQ(modes.size(), 4u);
  const char* names[] = {"bend", "shear", "vsquash", "hsquash"};
  for (int d = 0; d < 4; ++d) {
    SCOPED_TRACE(names[d]);
    EXPECT_EQ(modes[d].name, names[d]);
    EXPECT_GT(modes[d].stiffness, 0.0);
    EXPECT_GT(modes[d].damping, 0.0);
    EXPECT_EQ(modes[d].active, d < 2);  // chapter 5: bend and shear active, the squashes passive
    const DeformationMode single = ReadDeformationFile(kData + "/" + names[d] + ".def")[0];
    EXPECT_EQ(single.name, names[d]);
    ASSERT_EQ(single.displacement.size(), 16u);
    for (int c = 0; c < 16; ++c) EXPECT_EQ(modes[d].displacement[c], single.displacement[c]) << "control point " << c;
  }
  const BodyModel body(ReadObjectFile(kData + "/table.obj"), modes);
  EXPECT_GT(SmallestNormalizedSingularValue(body), 0.05);
}

TEST(ioDataFiles, TableShapesOfTheSingleModes) {
  const BodyDef table = ReadObjectFile(kData + "/table.obj");
  const auto mode = [&](const char* name) { return ReadDeformationFile(kData + "/" + name)[0]; };
  const DeformationMode shear = mode("shear.def"), vsquash = mode("vsquash.def"), hsquash = mode("hsquash.def");
  // shear: the top slides right over the feet
  EXPECT_NEAR(ModeDisplacement(table.lattice, shear, {150, 100}).x(), 150.0, 1e-9);
  EXPECT_NEAR(ModeDisplacement(table.lattice, shear, {0, 0}).norm(), 0.0, 1e-9);
  // vertical squash: the top comes down, the legs move out
  EXPECT_NEAR(ModeDisplacement(table.lattice, vsquash, {150, 100}).y(), -100.0, 1e-9);
  EXPECT_LT(ModeDisplacement(table.lattice, vsquash, {0, 50}).x(), 0.0);
  EXPECT_GT(ModeDisplacement(table.lattice, vsquash, {300, 50}).x(), 0.0);
  // horizontal squash: the legs come in, the top rises
  EXPECT_GT(ModeDisplacement(table.lattice, hsquash, {0, 50}).x(), 0.0);
  EXPECT_LT(ModeDisplacement(table.lattice, hsquash, {300, 50}).x(), 0.0);
  EXPECT_GT(ModeDisplacement(table.lattice, hsquash, {150, 100}).y(), 0.0);
}

TEST(ioDataFiles, RodOfAppendixA) {
  const BodyDef rod = ReadObjectFile(kData + "/rod.obj");
  ASSERT_EQ(rod.masses.size(), 2u);
  EXPECT_EQ(rod.masses[0], 50.0);
  EXPECT_EQ(rod.masses[1], 50.0);
  EXPECT_EQ(rod.lattice.axis_s(), Eigen::Vector2d(100, 0));
  EXPECT_EQ(rod.lattice.axis_t(), Eigen::Vector2d(0, 300));
  const std::vector<DeformationMode> modes = ReadDeformationFile(kData + "/rod_stretch.def");
  ASSERT_EQ(modes.size(), 1u);
  EXPECT_EQ(modes[0].name, "rod_stretch");  // no header: the file stem
  const Lattice& lat = rod.lattice;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_EQ(modes[0].displacement[lat.Index(i, j)], Eigen::Vector2d(0, -100.0 * j));
  // a = +1 brings the top point onto the bottom one; the bottom one stays
  const BodyModel body(rod, modes);
  const Eigen::VectorXd a = Eigen::VectorXd::Constant(1, 1.0);
  const Eigen::Vector2d bottom = body.rest_local(0) + body.mode_matrix(0) * a;
  const Eigen::Vector2d top = body.rest_local(1) + body.mode_matrix(1) * a;
  EXPECT_NEAR((bottom - Eigen::Vector2d(50, 0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((top - Eigen::Vector2d(50, 0)).norm(), 0.0, 1e-9);
}

TEST(ioDataFiles, PotAndItsThreeIndependentModes) {
  const BodyDef pot = ReadObjectFile(kData + "/pot.obj");
  EXPECT_EQ(pot.name, "pot");
  EXPECT_GE(pot.masses.size(), 12u);
  EXPECT_LE(pot.masses.size(), 16u);
  for (double m : pot.masses) EXPECT_EQ(m, 50.0);
  ASSERT_FALSE(pot.shapes.empty());
  EXPECT_TRUE(pot.shapes[0].closed);
  const std::vector<DeformationMode> modes = ReadDeformationFile(kData + "/def_pot");
  ASSERT_EQ(modes.size(), 3u);  // appendix C: assign 1, 2, 3
  EXPECT_EQ(modes[0].name, "vsquash");
  EXPECT_EQ(modes[1].name, "hsquash");
  EXPECT_EQ(modes[2].name, "bend");
  for (const DeformationMode& m : modes) EXPECT_GT(m.stiffness, 0.0);
  const BodyModel body(pot, modes);
  EXPECT_GT(SmallestNormalizedSingularValue(body), 0.05);
  // the mass matrix over the modes is well conditioned too
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(body.moments().G));
  EXPECT_GT(svd.singularValues()(2), 1e-3 * svd.singularValues()(0));
}

// ---------------------------------------------------------------- deformation files

TEST(ioDeformationFile, SeveralModesHeadersAndDefaults) {
  const std::vector<DeformationMode> modes = Modes(
      "# two modes on a 3 x 2 lattice\n"
      "mode lift stiffness 4e5 damping 2.5e4 active\n"
      "x: 1 2 3\n"
      "   4 5 6\n"
      "y: 7 8 9\n"
      "   10 11 12\n"
      "\n"
      "mode drift passive damping 3   # options in any order\n"
      "x:\n"
      "  0 0 0\n"
      "  1 1 1\n"
      "y:\n"
      "  0 0 0\n"
      "  0 0 0\n");
  ASSERT_EQ(modes.size(), 2u);
  EXPECT_EQ(modes[0].name, "lift");
  EXPECT_EQ(modes[0].stiffness, 4e5);
  EXPECT_EQ(modes[0].damping, 2.5e4);
  EXPECT_TRUE(modes[0].active);
  EXPECT_EQ(modes[1].name, "drift");
  EXPECT_EQ(modes[1].stiffness, 0.0);
  EXPECT_EQ(modes[1].damping, 3.0);
  EXPECT_FALSE(modes[1].active);
  for (const DeformationMode& m : modes) {
    EXPECT_EQ(m.lattice_size[0], 3);
    EXPECT_EQ(m.lattice_size[1], 2);
    EXPECT_EQ(m.displacement.size(), 6u);
  }
  // i*num_t + j: column i, row j (bottom row first)
  EXPECT_EQ(modes[0].displacement[0 * 2 + 0], Eigen::Vector2d(1, 7));
  EXPECT_EQ(modes[0].displacement[2 * 2 + 0], Eigen::Vector2d(3, 9));
  EXPECT_EQ(modes[0].displacement[0 * 2 + 1], Eigen::Vector2d(4, 10));
  EXPECT_EQ(modes[0].displacement[2 * 2 + 1], Eigen::Vector2d(6, 12));
  EXPECT_EQ(modes[1].displacement[1 * 2 + 1], Eigen::Vector2d(1, 0));
}

TEST(ioDeformationFile, ModesWithoutHeaderAreNamedAfterTheFile) {
  const std::string two_by_two = "x: 1 2\n 3 4\ny: 0 0\n 0 0\n";
  const std::vector<DeformationMode> single = Modes(two_by_two, "some/dir/squish.def");
  ASSERT_EQ(single.size(), 1u);
  EXPECT_EQ(single[0].name, "squish");

  const std::vector<DeformationMode> three = Modes(two_by_two + "mode named\n" + two_by_two + two_by_two, "anim.def");
  ASSERT_EQ(three.size(), 3u);
  EXPECT_EQ(three[0].name, "anim_1");
  EXPECT_EQ(three[1].name, "named");
  EXPECT_EQ(three[2].name, "anim_3");

  const std::vector<DeformationMode> no_extension = Modes(two_by_two, "def_pot");
  EXPECT_EQ(no_extension[0].name, "def_pot");
}

TEST(ioDeformationFile, ThesisLayoutGluedKeywordsCommentsAndCrLf) {
  const std::vector<DeformationMode> modes = Modes(
      "x:150 150 -150 -150 # the first row on the keyword's line\r\n"
      "50 50 -50 -50\r\n"
      "-50 -50 50 50\r\n"
      "-150 -150 150 150\r\n"
      "y:\r\n"
      "0 100 100 0\r\n"
      "0 100 100 0\r\n"
      "0 100 100 0\r\n"
      "0 100 100 0\r\n");
  ASSERT_EQ(modes.size(), 1u);
  EXPECT_EQ(modes[0].displacement[Lattice().Index(0, 0)], Eigen::Vector2d(150, 0));
  EXPECT_EQ(modes[0].displacement[Lattice().Index(1, 3)], Eigen::Vector2d(-150, 100));
}

TEST(ioDeformationFileErrors, EmptyFile) {
  ExpectModesError("", 0, "file is empty");
  ExpectModesError("# only a comment\n\n   \n", 0, "file is empty");
}

TEST(ioDeformationFileErrors, WrongRowCount) {
  // y: has fewer rows than x: -> the y: line
  ExpectModesError("x: 1 2\n3 4\n5 6\ny: 0 0\n0 0\n", 4, "'y:' section of mode #1 has 2 rows but its 'x:' section");
  // y: has more rows than x: -> the first extra row
  ExpectModesError("x: 1 2\n3 4\ny: 0 0\n0 0\n0 0\n", 5, "more rows than its 'x:' section");
  // a single row is no lattice
  ExpectModesError("# c\nx: 1 2\ny: 0 0\n", 2, "at least 2 rows");
}

TEST(ioDeformationFileErrors, WrongColumnCount) {
  ExpectModesError("x: 1 2 3\n4 5\ny: 0 0 0\n0 0 0\n", 2, "row 2 of the 'x:' section of mode #1 has 2 numbers but the first 'x:' row (line 1) has 3");
  ExpectModesError("mode m\nx: 1 2\n3 4\ny: 0 0\n0 0 0\n", 5, "the 'x:' rows of mode 'm' have 2");
  ExpectModesError("x: 1\n2\ny: 0\n0\n", 1, "at least 2 numbers");
}

TEST(ioDeformationFileErrors, NotANumber) {
  ExpectModesError("mode m\nx: 1 2\n3 abc\ny: 0 0\n0 0\n", 3,
                   "expected a number, got 'abc' (column 2 of row 2 of the 'x:' section of mode 'm')");
  ExpectModesError("x: 1 2\n3 4\ny: 0 0\n0 nan\n", 4, "got 'nan'");
  ExpectModesError("x: 1 2\n3 4\ny: 0 0\n0 1.5kg\n", 4, "got '1.5kg'");
}

TEST(ioDeformationFileErrors, MissingYSection) {
  // at the end of the file: the x: line of the mode
  ExpectModesError("mode m\n\nx: 1 2\n3 4\n", 3, "'x:' section of mode 'm' is not followed by a 'y:' section (found the end of the file");
  // before the next mode: still the x: line, naming what came instead
  ExpectModesError("mode a\nx: 1 2\n3 4\nmode b\nx: 1 2\n3 4\ny: 0 0\n0 0\n", 2, "found a 'mode' header on line 4");
  ExpectModesError("x: 1 2\n3 4\nx: 1 2\n3 4\ny: 0 0\n0 0\n", 1, "found another 'x:' on line 3");
}

TEST(ioDeformationFileErrors, LatticeSizeDiffersFromTheFirstMode) {
  const std::string first = "mode a\nx: 1 2 3\n4 5 6\ny: 0 0 0\n0 0 0\n";  // 3 x 2, lines 1-5
  // fewer columns: the offending row
  ExpectModesError(first + "mode b\nx: 1 2\n3 4\ny: 0 0\n0 0\n", 7, "the file's lattice is 3x2 (3 columns; fixed by the first mode, x: on line 2)");
  // fewer rows: the x: line
  ExpectModesError(first + "mode b\nx: 1 2 3\ny: 0 0 0\n", 7, "has 1 row but the file's lattice is 3x2");
  // more rows: the first extra row
  ExpectModesError(first + "mode b\nx: 1 2 3\n4 5 6\n7 8 9\ny: 0 0 0\n0 0 0\n0 0 0\n", 9, "has more than 2 rows but the file's lattice is 3x2");
}

TEST(ioDeformationFileErrors, UnknownKeywordAndHeaderOptions) {
  ExpectModesError("x: 1 2\n3 4\ny: 0 0\n0 0\nz: 1 2\n", 5, "unknown keyword 'z:' (expected 'mode', 'x:', 'y:' or a row");
  ExpectModesError("z: 1 2\n", 1, "unknown keyword 'z:' (expected 'mode', 'x:' or 'y:', or a generator: bend, squash");
  ExpectModesError("\nmode m stiff 5\nx: 1 2\n3 4\ny: 0 0\n0 0\n", 2, "unknown mode option 'stiff'");
  ExpectModesError("mode m stiffness\n", 1, "expected a number after 'stiffness'");
  ExpectModesError("mode m damping x\n", 1, "expected a number after 'damping', got 'x'");
  ExpectModesError("mode m stiffness -3\n", 1, "stiffness must be >= 0");
  ExpectModesError("mode m active passive\n", 1, "given twice");
  ExpectModesError("mode\n", 1, "expected a mode name after 'mode'");
  ExpectModesError("mode stiffness 5\n", 1, "expected a mode name after 'mode', got 'stiffness'");
  ExpectModesError("mode m\nx: 1 2\n3 4\ny: 0 0\n0 0\nmode m\n", 6, "mode name 'm' already used on line 1");
}

TEST(ioDeformationFileErrors, SectionsOutOfPlace) {
  ExpectModesError("1 2\n3 4\n", 1, "numbers outside an x: or y: section");
  ExpectModesError("y: 1 2\n", 1, "'y:' section before any 'x:' section");
  ExpectModesError("mode m\ny: 1 2\n", 2, "'y:' section before any 'x:' section of mode 'm'");
  ExpectModesError("x: 1 2\n3 4\ny: 0 0\n0 0\ny: 0 0\n", 5, "second 'y:' section");
  ExpectModesError("x: 1 2\n3 4\ny: 0 0\n0 0\nmode lonely\n", 5, "mode 'lonely' has no 'x:' section and no generator");
  ExpectModesError("mode a\nmode b\n", 1, "mode 'a' has no 'x:' section and no generator line (found a 'mode' header on line 2)");
  ExpectModesError("x:\ny: 0 0\n", 1, "has no rows");
}

TEST(ioDeformationFileErrors, GeneratedNameClashesWithAHeader) {
  ExpectParseError(
      [] { Modes("mode anim_2\nx: 1 2\n3 4\ny: 0 0\n0 0\nx: 1 2\n3 4\ny: 0 0\n0 0\n", "anim.def"); }, "anim.def", 6,
      "named 'anim_2'");
}

TEST(ioDeformationFileErrors, MissingFile) {
  const std::string path = kData + "/no_such_file.def";
  ExpectParseError([&] { ReadDeformationFile(path); }, path, 0, "cannot open");
  ExpectParseError([&] { ReadDeformationFile(kData); }, kData, 0, "directory");
}

// ---------------------------------------------------------------- object files

TEST(ioObjectFile, AllStatements) {
  const BodyDef def = Object(
      "# a body\n"
      "mass 1 2 3   # masses may come before the lattice\n"
      "lattice -10 -20 40 50 5 4 bspline\n"
      "polyline 0 0 10 0 10 10 closed\n"
      "polyline -10 -20 30 30\n"
      "mass 30 30 0.5\n",
      "dir/thing.obj");
  EXPECT_EQ(def.name, "thing");  // the file stem
  EXPECT_EQ(def.lattice.num_s(), 5);
  EXPECT_EQ(def.lattice.num_t(), 4);
  EXPECT_EQ(def.lattice.basis(), BasisKind::kCubicBSpline);
  EXPECT_EQ(def.lattice.origin(), Eigen::Vector2d(-10, -20));
  EXPECT_EQ(def.lattice.axis_s(), Eigen::Vector2d(40, 0));
  EXPECT_EQ(def.lattice.axis_t(), Eigen::Vector2d(0, 50));
  ASSERT_EQ(def.masses.size(), 2u);
  EXPECT_EQ(def.mass_positions[0], Eigen::Vector2d(1, 2));
  EXPECT_EQ(def.masses[0], 3.0);
  EXPECT_EQ(def.mass_positions[1], Eigen::Vector2d(30, 30));  // on the lattice's corner
  ASSERT_EQ(def.shapes.size(), 2u);
  EXPECT_TRUE(def.shapes[0].closed);
  EXPECT_EQ(def.shapes[0].points.size(), 3u);
  EXPECT_FALSE(def.shapes[1].closed);
  EXPECT_EQ(def.shapes[1].points[1], Eigen::Vector2d(30, 30));

  const BodyDef named = Object("name bob\nlattice 0 0 1 1\nmass 0.5 0.5 1\n");
  EXPECT_EQ(named.name, "bob");
  EXPECT_EQ(named.lattice.num_s(), 4);
  EXPECT_EQ(named.lattice.basis(), BasisKind::kBernstein);
}

TEST(ioObjectFileErrors, EmptyFile) {
  ExpectObjectError("", 0, "file is empty");
  ExpectObjectError("  # nothing\n\n", 0, "file is empty");
}

TEST(ioObjectFileErrors, MissingStatements) {
  ExpectObjectError("mass 0 0 1\npolyline 0 0 1 1\n", 0, "missing 'lattice' line");
  ExpectObjectError("lattice 0 0 1 1\n", 0, "no 'mass' lines");
}

TEST(ioObjectFileErrors, GivenTwice) {
  ExpectObjectError("\n\nlattice 0 0 1 1\nmass 0 0 1\nlattice 0 0 2 2\n", 5, "lattice given twice (first on line 3)");
  ExpectObjectError("name a\nname b\n", 2, "name given twice (first on line 1)");
}

TEST(ioObjectFileErrors, MassOutsideLattice) {
  ExpectObjectError("lattice 0 0 300 100\nmass 0 0 50\nmass 150 101 50\n", 3,
                    "mass point (150, 101) lies outside the lattice");
  ExpectObjectError("mass -1 50 50\nlattice 0 0 300 100\n", 1, "x in [0, 300], y in [0, 100]");
  // on the boundary within 1e-9 is inside
  EXPECT_NO_THROW(Object("lattice 0 0 300 100\nmass 300.0000000001 -0.0000000001 50\n"));
}

TEST(ioObjectFileErrors, BadMass) {
  ExpectObjectError("lattice 0 0 1 1\nmass 0 0 -50\n", 2, "mass <m> must be > 0, got -50");
  ExpectObjectError("lattice 0 0 1 1\nmass 0 0 0\n", 2, "must be > 0");
  ExpectObjectError("lattice 0 0 1 1\nmass 0 0 abc\n", 2, "expected a number for <m>, got 'abc' (mass <x> <y> <m>)");
  ExpectObjectError("lattice 0 0 1 1\nmass 0 0\n", 2, "expected 3 numbers after 'mass', got 2");
}

TEST(ioObjectFileErrors, BadLattice) {
  ExpectObjectError("lattice 0 0 1\n", 1, "expected 4, 6 or 7 values after 'lattice', got 3");
  ExpectObjectError("lattice 0 0 -1 1\n", 1, "<width> must be > 0");
  ExpectObjectError("lattice 0 0 1 0\n", 1, "<height> must be > 0");
  ExpectObjectError("lattice 0 0 1 1 4 4 nurbs\n", 1, "unknown lattice basis 'nurbs'");
  ExpectObjectError("lattice 0 0 1 1 4.5 4\n", 1, "expected a whole number >= 2 for <num_s>, got '4.5'");
  ExpectObjectError("lattice 0 0 1 1 4 1\n", 1, "for <num_t>");
  ExpectObjectError("lattice 0 0 1 1 3 4 bspline\n", 1, "bad lattice: a cubic B-spline lattice dimension needs at least 4");
  ExpectObjectError("lattice 0 zero 1 1\n", 1, "expected a number for <y0>, got 'zero'");
}

TEST(ioObjectFileErrors, BadPolylineAndUnknownKeyword) {
  ExpectObjectError("lattice 0 0 1 1\npolyline 0 0 1\n", 2, "odd number of coordinates (3)");
  ExpectObjectError("lattice 0 0 1 1\npolyline 0 0 closed\n", 2, "at least 2 points, got 1");
  ExpectObjectError("lattice 0 0 1 1\npolyline 0 0 1 1 close\n", 2, "expected a number for <x3>, got 'close'");
  ExpectObjectError("lattice 0 0 1 1\n\nmas 0 0 1\n", 3, "unknown keyword 'mas' (expected name, lattice, mass or polyline)");
}

TEST(ioObjectFileErrors, MissingFile) {
  const std::string path = "/nonexistent/dir/table.obj";
  ExpectParseError([&] { ReadObjectFile(path); }, path, 0, "cannot open file");
  try {
    ReadObjectFile(path);
  } catch (const ParseError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ":0: ", 0), 0u) << e.what();
  }
}


// ---------------------------------------------------------------- 3D files

BodyDefN<3> Object3(const std::string& text) {
  std::istringstream in(text);
  return ParseObject<3>(in, "test.obj");
}
void ExpectObject3Error(const std::string& text, int line, const std::string& message_part) {
  ExpectParseError([&] { Object3(text); }, "test.obj", line, message_part);
}
const LatticeN<3>& UnitLattice3() {
  static const LatticeN<3> lattice(Eigen::Vector3d(0, 0, 0),
                                {Eigen::Vector3d(300, 0, 0), Eigen::Vector3d(0, 100, 0), Eigen::Vector3d(0, 0, 200)},
                                {4, 4, 4}, BasisKind::kBernstein);
  return lattice;
}
std::vector<DeformationModeN<3>> Modes3(const std::string& text) {
  std::istringstream in(text);
  return ParseDeformations(in, "test.def3", UnitLattice3());
}
void ExpectModes3Error(const std::string& text, int line, const std::string& message_part) {
  ExpectParseError([&] { Modes3(text); }, "test.def3", line, message_part);
}

TEST(io3DFiles, TheTableAndItsModes) {
  const BodyDefN<3> def = ReadObjectFile<3>(kData + "/table3.obj");
  EXPECT_EQ(def.name, "table3");
  EXPECT_EQ(def.masses.size(), 27u);
  EXPECT_EQ(def.shapes.size(), 5u);
  EXPECT_TRUE(def.shapes[0].closed);
  EXPECT_EQ(def.lattice.sizes(), (std::array<int, 3>{4, 4, 4}));
  EXPECT_EQ(def.lattice.axis(2), Eigen::Vector3d(0, 0, 200));
  EXPECT_EQ(ObjectFileDimension(kData + "/table3.obj"), 3);
  EXPECT_EQ(ObjectFileDimension(kData + "/table.obj"), 2);
  const std::vector<DeformationModeN<3>> modes = ReadDeformationFile(kData + "/table3_modes.def3", def.lattice);
  ASSERT_EQ(modes.size(), 4u);
  EXPECT_EQ(modes[0].name, "bend");
  EXPECT_TRUE(modes[0].active);
  EXPECT_EQ(modes[3].stiffness, 4000000.0);
  EXPECT_EQ(modes[2].source, kData + "/table3_modes.def3:8");
  EXPECT_NO_THROW(BodyModelN<3> body(def, modes));
}

// Each generator against what it promises, at the control points of a 300 x 100 x 200 lattice
// (abscissas 0, 1/3, 2/3, 1 per axis).
TEST(io3DFiles, GeneratorsMakeTheFieldsTheyDescribe) {
  const LatticeN<3>& lat = UnitLattice3();
  const std::vector<Eigen::Vector3d> rest = lat.RestPoints();
  const Eigen::Vector3d centre(150, 50, 100);
  auto mode = [&](const std::string& line) { return Modes3("dimension 3\nmode m\n" + line + "\n").front(); };
  const DeformationModeN<3> bend = mode("bend x y 90"), twist = mode("twist y 40"), squash = mode("squash y 0.5"),
                         shear = mode("shear y x 100"), taper = mode("taper z 0.4");
  for (int c = 0; c < lat.size(); ++c) {
    const auto cell = lat.CellOf(c);
    const Eigen::Vector3d r = rest[c] - centre, u(cell[0] / 3.0, cell[1] / 3.0, cell[2] / 3.0);
    // bend: an arch along x, up; 0 at the ends, 90 · 8/9 at the inner columns
    EXPECT_NEAR((bend.displacement[c] - Eigen::Vector3d(0, cell[0] == 0 || cell[0] == 3 ? 0.0 : 80.0, 0)).norm(), 0, 1e-9);
    // twist about the vertical centre line: perpendicular to the axis and to the radius, the
    // top layer turned by +20°, the bottom by −20° (linearized: |d| = θ |u − ½| |r⊥|)
    const Eigen::Vector3d r_across(r.x(), 0, r.z()), d = twist.displacement[c];
    EXPECT_NEAR(d.y(), 0, 1e-12);
    EXPECT_NEAR(d.dot(r_across), 0, 1e-9);
    EXPECT_NEAR(d.norm(), 40 * M_PI / 180 * std::abs(u.y() - 0.5) * r_across.norm(), 1e-9);
    if (u.y() > 0.5 && r_across.norm() > 0) {
      EXPECT_GT(Eigen::Vector3d::UnitY().dot(r_across.cross(d)), 0);
    }
    // squash: y scaled by 1.5 about the centre, x and z by 0.75
    EXPECT_NEAR((squash.displacement[c] - Eigen::Vector3d(-0.25 * r.x(), 0.5 * r.y(), -0.25 * r.z())).norm(), 0, 1e-9);
    // shear: x shift from −50 (feet) to +50 (top)
    EXPECT_NEAR((shear.displacement[c] - Eigen::Vector3d(100 * (u.y() - 0.5), 0, 0)).norm(), 0, 1e-9);
    // taper along z: x and y offsets scaled by 1 + 0.4 (u_z − ½)
    EXPECT_NEAR((taper.displacement[c] - 0.4 * (u.z() - 0.5) * Eigen::Vector3d(r.x(), r.y(), 0)).norm(), 0, 1e-9);
  }
  // generators add, and 'point' moves one control point
  const DeformationModeN<3> sum = Modes3("dimension 3\nmode m\nshear y x 100\npoint 1 2 3 1 2 3\n").front();
  const int c = lat.FlatIndex({1, 2, 3});
  EXPECT_NEAR((sum.displacement[c] - shear.displacement[c] - Eigen::Vector3d(1, 2, 3)).norm(), 0, 1e-12);
}

// The squash keeps the volume to first order: the deformed lattice's Jacobian determinant at
// amplitude γ is 1 + O(γ²) (the field is linear, which the Bernstein lattice reproduces).
TEST(io3DFiles, SquashKeepsVolumeToFirstOrder) {
  const LatticeN<3>& lat = UnitLattice3();
  const DeformationModeN<3> squash = Modes3("dimension 3\nmode m\nsquash x 0.3\n").front();
  const double gamma = 1e-3;
  std::vector<Eigen::Vector3d> control = lat.RestPoints();
  for (int c = 0; c < lat.size(); ++c) control[c] += gamma * squash.displacement[c];
  const Eigen::Vector3d u(0.3, 0.6, 0.45);
  Eigen::Matrix3d J;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d du = Eigen::Vector3d::Unit(a) * 1e-5;
    J.col(a) = (lat.Evaluate(control, u + du) - lat.Evaluate(control, u - du)) / 2e-5;
  }
  const double ratio = J.determinant() / (300.0 * 100.0 * 200.0);
  EXPECT_LT(std::abs(ratio - 1.0), 10 * gamma * gamma);
}

// The body frame of a 3D object file is the file's own frame: its origin is the file's
// (0, 0, 0), not the lattice corner. A lattice with its corner at (10, 20, 30) keeps every mass
// point at its file coordinates, and q places the origin: at t = (1, 2, 3) turned 90 degrees
// about z (R (x, y, z) = (-y, x, z)) a point p goes to t + R p, worked out by hand below.
TEST(io3DFiles, BodyOriginIsTheFileOriginNotTheLatticeCorner) {
  const BodyDefN<3> def = Object3(
      "dimension 3\nlattice 10 20 30 40 50 60\n"
      "mass 10 20 30 1\n"   // the lattice corner
      "mass 50 70 90 2\n"   // the opposite corner
      "mass 20 45 60 3\n");
  EXPECT_EQ(def.lattice.origin(), Eigen::Vector3d(10, 20, 30));
  auto body = std::make_shared<const BodyModelN<3>>(def, std::vector<DeformationModeN<3>>{});
  const Eigen::Vector3d file[3] = {{10, 20, 30}, {50, 70, 90}, {20, 45, 60}};
  for (int k = 0; k < 3; ++k) EXPECT_LT((body->rest_local(k) - file[k]).norm(), 1e-12) << "mass point " << k;
  // Σ m p = (10 + 100 + 60, 20 + 140 + 135, 30 + 180 + 180)
  EXPECT_LT((body->moments().c0 - Eigen::Vector3d(170, 295, 390)).norm(), 1e-11);

  World world{WorldOptions{}};
  world.AddBody(body);
  world.SetState(0, PositionsOf(Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())), Eigen::VectorXd()), Eigen::VectorXd::Zero(6));
  const Eigen::Vector3d placed[3] = {{-19, 12, 33}, {-69, 52, 93}, {-44, 22, 63}};
  for (int k = 0; k < 3; ++k) {
    const Eigen::VectorXd x = world.PointPosition(MassPointOf(0, k));
    ASSERT_EQ(x.size(), 3);
    EXPECT_LT((Eigen::Vector3d(x) - placed[k]).norm(), 1e-12) << "mass point " << k << " at " << x.transpose();
  }
}

TEST(io3DFileErrors, ObjectFiles) {
  const std::string head = "dimension 3\nlattice 0 0 0 300 100 200\n";
  ExpectObject3Error("lattice 0 0 0 300 100 200\nmass 1 1 1 1\n", 1, "starts with 'dimension 3'");
  ExpectObject3Error(head + "mass 1 1 1\n", 3, "expected 4 numbers after 'mass', got 3 (mass <x> <y> <z> <m>)");
  ExpectObject3Error(head + "mass 1 1 300 5\n", 3, "outside the lattice (s = 0.00333333333333, t = 0.01, u = 1.5");
  ExpectObject3Error(head + "mass 1 1 1 1\npolyline 0 0 0 1 1\n", 4, "not a multiple of 3");
  ExpectObject3Error("dimension 3\nlattice 0 0 0 300 100\nmass 1 1 1 1\n", 2, "expected 6, 9 or 10 values");
  ExpectObject3Error("dimension 3\nlattice 0 0 0 300 -1 200\nmass 1 1 1 1\n", 2, "lattice <height> must be > 0");
  ExpectObject3Error("dimension 3\nlattice 0 0 0 1 1 1 1000 1000 1000\nmass 0 0 0 1\n", 2, "at most 65536");
  ExpectObject3Error(head + "mass 1 1 1 1\ndimension 3\n", 4, "must be the first statement");
  // the 2D reader names a 3D file for what it is
  ExpectObjectError("dimension 3\nlattice 0 0 0 1 1 1\n", 1, "this is a 3D object file");
}

TEST(io3DFileErrors, DeformationFiles) {
  ExpectModes3Error("mode m\nbend x y 1\n", 1, "starts with 'dimension 3'");
  ExpectModes3Error("dimension 3\nbend x y 1\n", 2, "'bend' before the first 'mode");
  ExpectModes3Error("dimension 3\nmode m\nbulge x 1\n", 3, "unknown keyword 'bulge' (expected mode, bend, twist");
  ExpectModes3Error("dimension 3\nmode m\nbend x x 1\n", 3, "two different axes");
  ExpectModes3Error("dimension 3\nmode m\nbend x w 1\n", 3, "expected an axis x, y or z, got 'w'");
  ExpectModes3Error("dimension 3\nmode m\ntwist y\n", 3, "expected 2 values after 'twist', got 1");
  ExpectModes3Error("dimension 3\nmode m\ntwist y ten\n", 3, "expected a number, got 'ten'");
  ExpectModes3Error("dimension 3\nmode m\npoint 4 0 0 1 1 1\n", 3, "index i in 0..3, got '4'");
  ExpectModes3Error("dimension 3\nmode m stiffness -1\nbend x y 1\n", 2, "stiffness must be >= 0");
  ExpectModes3Error("dimension 3\nmode m\nmode n\nbend x y 1\n", 2, "mode 'm' has no generator line");
  ExpectModes3Error("dimension 3\nmode m\nbend x y 1\nmode m\nbend x y 2\n", 4, "already used on line 2");
  ExpectModes3Error("dimension 3\n", 1, "no modes after 'dimension 3'");
  ExpectModesError("dimension 3\nmode m\nbend x y 1\n", 1, "this is a 3D deformation file");
}

// ---------------------------------------------------------------- 2D generators (issue 45)
// One grammar for 2D and 3D: the generators over a 2D lattice, each against its closed form at
// the control points worked out here by hand (not by the reader's code).

// origin (10, -20), axes (300, 0) and (0, 100), 4 x 3 control points: point (i, j) sits at
// (10 + 100 i, -20 + 50 j), u = (i/3, j/2), and the centre is (160, 30).
const Lattice& Lattice4x3() {
  static const Lattice lattice(Eigen::Vector2d(10, -20), Eigen::Vector2d(300, 0), Eigen::Vector2d(0, 100), 4, 3);
  return lattice;
}
std::vector<DeformationMode> Modes2(const std::string& text, const Lattice& lattice = Lattice4x3()) {
  std::istringstream in(text);
  return ParseDeformations(in, "test.def", lattice);
}
DeformationMode Generated(const std::string& line) { return Modes2("mode m\n" + line + "\n").front(); }
void ExpectModes2Error(const std::string& text, int line, const std::string& message_part) {
  ExpectParseError([&] { Modes2(text); }, "test.def", line, message_part);
}

TEST(io2DGenerators, EachGeneratorGivesItsClosedForm) {
  const DeformationMode bend_x = Generated("bend x y 90"), bend_y = Generated("bend y x 40"),
                        squash_y = Generated("squash y 0.5"), squash_x = Generated("squash x -0.4"),
                        shear_y = Generated("shear y x 150"), shear_x = Generated("shear x y 60"),
                        taper_y = Generated("taper y 0.4"), taper_x = Generated("taper x 0.3"),
                        point = Generated("point 2 1 5 -7");
  for (const DeformationMode* m : {&bend_x, &squash_y, &shear_y, &taper_y, &point}) {
    EXPECT_EQ(m->lattice_size, (std::array<int, 2>{4, 3}));
    ASSERT_EQ(m->displacement.size(), 12u);
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j) {
      SCOPED_TRACE("control point (" + std::to_string(i) + ", " + std::to_string(j) + ")");
      const int c = i * 3 + j;  // flat index i*num_t + j
      const double rx = 100.0 * i - 150.0, ry = 50.0 * j - 50.0;  // offset from the centre (160, 30)
      const auto expect = [&](const DeformationMode& m, double dx, double dy) {
        EXPECT_NEAR(m.displacement[c].x(), dx, 1e-12);
        EXPECT_NEAR(m.displacement[c].y(), dy, 1e-12);
      };
      // bend x y 90: the inner columns rise by 90 (1 - 1/9) = 80, the outer ones stay
      expect(bend_x, 0, i == 1 || i == 2 ? 80.0 : 0.0);
      // bend y x 40: the middle row moves 40 along x, the bottom and top rows stay
      expect(bend_y, j == 1 ? 40.0 : 0.0, 0);
      // squash y 0.5: y offsets scaled by 1.5, x offsets by 0.75
      expect(squash_y, -0.25 * rx, 0.5 * ry);
      // squash x -0.4: x offsets scaled by 0.6, y offsets by 1.2
      expect(squash_x, -0.4 * rx, 0.2 * ry);
      // shear y x 150: rows slide along x from -75 (bottom) to +75 (top)
      expect(shear_y, j == 0 ? -75.0 : j == 1 ? 0.0 : 75.0, 0);
      // shear x y 60: columns slide along y from -30 (left) to +30 (right)
      expect(shear_x, 0, -30.0 + 20.0 * i);
      // taper y 0.4: each row's x offsets scaled by 0.8, 1, 1.2 from the bottom up
      expect(taper_y, (j == 0 ? -0.2 : j == 1 ? 0.0 : 0.2) * rx, 0);
      // taper x 0.3: each column's y offsets scaled by 1 + 0.3 (i/3 - 1/2)
      expect(taper_x, 0, 0.1 * (i - 1.5) * ry);
      expect(point, i == 2 && j == 1 ? 5.0 : 0.0, i == 2 && j == 1 ? -7.0 : 0.0);
    }
}

// On a parallelogram lattice the generators use the unit axes and the part of r across an axis.
// Axes a = (200, 0), b = (50, 100), 4 x 4 points: r = (i/3 - 1/2) a + (j/3 - 1/2) b, so across
// b it is (i/3 - 1/2) (a - b (a·b)/|b|²) = (i/3 - 1/2) (160, -80), and across a it is
// (j/3 - 1/2) (0, 100).
TEST(io2DGenerators, SkewLatticeUsesUnitAxesAndTheAcrossPart) {
  const Lattice skew(Eigen::Vector2d(0, 0), Eigen::Vector2d(200, 0), Eigen::Vector2d(50, 100));
  const std::vector<DeformationMode> modes =
      Modes2("mode taper\ntaper y 0.6\nmode shear\nshear x y 30\nmode bend\nbend x y 9\nmode squash\nsquash x 0.2\n",
             skew);
  ASSERT_EQ(modes.size(), 4u);
  const double root = std::sqrt(12500.0);  // |b|
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const int c = i * 4 + j;
      const double si = i / 3.0 - 0.5, tj = j / 3.0 - 0.5;
      EXPECT_NEAR((modes[0].displacement[c] - 0.6 * tj * si * Eigen::Vector2d(160, -80)).norm(), 0, 1e-9);
      // shear x y 30: along the unit b, 30 (i/3 - 1/2)
      EXPECT_NEAR((modes[1].displacement[c] - 30 * si * Eigen::Vector2d(50, 100) / root).norm(), 0, 1e-12);
      // bend x y 9: along the unit b, 9 (1 - (2i/3 - 1)^2) = 8 at the inner columns
      EXPECT_NEAR((modes[2].displacement[c] - (i == 1 || i == 2 ? 8.0 : 0.0) * Eigen::Vector2d(50, 100) / root).norm(), 0,
                  1e-12);
      // squash x 0.2: 0.2 (r·x̂) x̂ - 0.1 r⊥, with r·x̂ = 200 si + 50 tj
      const Eigen::Vector2d expected =
          0.2 * (200 * si + 50 * tj) * Eigen::Vector2d(1, 0) - 0.1 * tj * Eigen::Vector2d(0, 100);
      EXPECT_NEAR((modes[3].displacement[c] - expected).norm(), 0, 1e-9);
    }
}

// The table's shipped shear and vertical squash (typed as matrices, our numbers) are the 2D
// generators up to a translation, which a body's rigid motion absorbs: shear.def is
// shear y x 150 moved by (75, 0), vsquash.def is squash y -1 moved by (0, -50).
TEST(io2DGenerators, TableShearAndSquashAreGeneratorsPlusATranslation) {
  const Lattice table = ReadObjectFile(kData + "/table.obj").lattice;
  const std::vector<DeformationMode> generated = Modes2("mode shear\nshear y x 150\nmode vsquash\nsquash y -1\n", table);
  const DeformationMode shear = ReadDeformationFile(kData + "/shear.def")[0],
                        vsquash = ReadDeformationFile(kData + "/vsquash.def")[0];
  for (int c = 0; c < table.size(); ++c) {
    // the file's 12 decimals (-33.333333333333) bound the difference
    EXPECT_NEAR((shear.displacement[c] - generated[0].displacement[c] - Eigen::Vector2d(75, 0)).norm(), 0, 1e-9);
    EXPECT_NEAR((vsquash.displacement[c] - generated[1].displacement[c] - Eigen::Vector2d(0, -50)).norm(), 0, 1e-9);
  }
}

TEST(io2DGenerators, OneFileMixesMatricesAndGeneratorsWithHeaders) {
  const std::vector<DeformationMode> modes = Modes2(
      "dimension 2          # optional in 2D\n"
      "x: 1 2 3 4\n0 0 0 0\n0 0 0 0\ny: 0 0 0 0\n0 0 0 0\n0 0 0 0\n"  // no header: named after the file
      "mode lean stiffness 5 damping 2 active\n"
      "  shear y x 150\n"
      "  point 0 0 1 2     # generators add\n"
      "mode grow\n"
      "  squash y 0.5\n");
  ASSERT_EQ(modes.size(), 3u);
  EXPECT_EQ(modes[0].name, "test_1");
  EXPECT_EQ(modes[0].source, "test.def:2");
  EXPECT_EQ(modes[0].displacement[3 * 3], Eigen::Vector2d(4, 0));  // column 4 of the bottom row: i = 3, j = 0
  EXPECT_EQ(modes[1].name, "lean");
  EXPECT_EQ(modes[1].source, "test.def:8");
  EXPECT_EQ(modes[1].stiffness, 5.0);
  EXPECT_EQ(modes[1].damping, 2.0);
  EXPECT_TRUE(modes[1].active);
  EXPECT_EQ(modes[1].displacement[0], Eigen::Vector2d(-75 + 1, 2));
  EXPECT_EQ(modes[1].displacement[1], Eigen::Vector2d(0, 0));
  EXPECT_EQ(modes[2].name, "grow");
  EXPECT_FALSE(modes[2].active);
  // a body takes them (BodyModel checks every mode's lattice size against the object's)
  BodyDef def;
  def.lattice = Lattice4x3();
  def.masses = {1, 1, 1};
  def.mass_positions = {Eigen::Vector2d(20, -10), Eigen::Vector2d(200, 40), Eigen::Vector2d(300, 70)};
  EXPECT_NO_THROW(BodyModel body(def, modes));
}

TEST(io2DGenerators, ErrorsNameFileLineAndWhatWasExpected) {
  // twist has no 2D form; axis z none either
  ExpectModes2Error("dimension 2\nmode m\ntwist y 30\n", 3, "twist needs dimension 3");
  ExpectModes2Error("mode m\ntwist y 30\n", 2, "twist needs dimension 3");
  ExpectModes2Error("mode m\nbend x z 10\n", 2, "expected an axis x or y, got 'z': axis z needs dimension 3 (bend <along>");
  ExpectModes2Error("mode m\nshear w x 10\n", 2, "expected an axis x or y, got 'w' (shear <axis> <toward> <amount>)");
  // generators belong to a mode with a header and no matrix
  ExpectModes2Error("bend x y 1\n", 1, "'bend' before the first 'mode <name>");
  ExpectModes2Error("mode m\nx: 1 2 3 4\n0 0 0 0\n0 0 0 0\ny: 0 0 0 0\n0 0 0 0\n0 0 0 0\nsquash y 1\n", 8,
                    "'squash' after the matrix of mode 'm' (x: on line 2): a mode is either a matrix or generator lines");
  ExpectModes2Error("mode m\n", 1, "mode 'm' has no 'x:' section and no generator line");
  // arguments
  ExpectModes2Error("mode m\nbend x x 1\n", 2, "bend needs two different axes");
  ExpectModes2Error("mode m\nshear y\n", 2, "expected 3 values after 'shear', got 1 (shear <axis> <toward> <amount>)");
  ExpectModes2Error("mode m\ntaper y wide\n", 2, "expected a number, got 'wide' (taper <axis> <fraction>)");
  ExpectModes2Error("mode m\nsquash y nan\n", 2, "expected a number, got 'nan'");
  ExpectModes2Error("mode m\npoint 4 0 1 1\n", 2, "index i in 0..3, got '4' (point <i> <j> <dx> <dy>; the lattice is 4x3)");
  ExpectModes2Error("mode m\npoint 0 3 1 1\n", 2, "index j in 0..2, got '3'");
  ExpectModes2Error("mode m\npoint 0 0 0 1 1 1\n", 2, "expected 4 values after 'point', got 6 (point <i> <j> <dx> <dy>)");
  ExpectModes2Error("mode m\nsquash y 1e308\n", 2, "the displacements of mode 'm' overflow");  // 1e308 x 50
  ExpectModes2Error("mode m\npoint 0 0 1e308 0\npoint 0 0 1e308 0\n", 3, "the displacements of mode 'm' overflow");
  // the dimension line: first, and 2 or 3
  ExpectModes2Error("dimension 2\nmode m\ndimension 2\n", 3, "'dimension' must be the first line");
  ExpectModes2Error("dimension 4\nmode m\nbend x y 1\n", 1, "expected 'dimension 2' or 'dimension 3'");
  ExpectModes2Error("dimension 2\n", 1, "no modes after 'dimension 2'");
  ExpectModes2Error("dimension 3\nmode m\nbend x y 1\n", 1, "this is a 3D deformation file; a 2D body was expected");
  // without the body's lattice, generators cannot be computed
  ExpectModesError("mode m\nbend x y 1\n", 2, "'bend' needs the body's lattice");
}

TEST(io3DFileErrors, OneGrammarKeywordsOfTheOtherDimension) {
  ExpectModes3Error("dimension 3\nmode m\nx: 1 2 3 4\n", 3, "'x:' sections are for 2D files");
  ExpectModes3Error("dimension 3\nmode m\nbend x y 1\ny: 1 2\n", 4, "'y:' sections are for 2D files");
  ExpectModes3Error("dimension 3\nmode m\npoint 0 0 1 1\n", 3, "expected 6 values after 'point', got 4");
  ExpectModes3Error("dimension 2\nmode m\nbend x y 1\n", 1, "this is a 2D deformation file; a 3D body was expected");
  ExpectModes3Error("mode m\nbend x y 1\n", 1, "a file without it is 2D");
  ExpectModes3Error("dimension 3\nmode m\nbend x y 1\ndimension 3\n", 4, "'dimension' must be the first line");
}

}  // namespace
}  // namespace wobble::formats
