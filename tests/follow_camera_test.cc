// The follow camera (pipelines/follow_camera.h): boxes of one size that keep the body in view,
// the ground a fifth up when it can be, and a smoothed path that follows a body moving at
// constant velocity exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "pipelines/follow_camera.h"

namespace wobble::pipelines {
namespace {

Eigen::AlignedBox2d Table(double x, double y) { return Eigen::AlignedBox2d(Eigen::Vector2d(x, y), Eigen::Vector2d(x + 300, y + 100)); }

TEST(FollowCamera, FollowsConstantVelocityExactlyAtOneScale) {
  std::vector<FollowMoment> moments;
  for (int i = 0; i <= 90; ++i) {
    const double t = i / 30.0;
    moments.push_back({t, Table(-100 + 400 * t, 50 + 120 * t), std::nullopt});
  }
  const std::vector<Eigen::AlignedBox2d> boxes = FollowBoxes(moments, {4.0 / 3.0, 1.8, 0.15});
  ASSERT_EQ(boxes.size(), moments.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_LT((boxes[i].center() - moments[i].body.center()).norm(), 1e-9) << i;  // first and last too
    EXPECT_NEAR(boxes[i].sizes().x() / boxes[i].sizes().y(), 4.0 / 3.0, 1e-12);
    // the table's half-width 150 is the largest half-extent: 1.8 x 150 / (4/3) high
    EXPECT_NEAR(boxes[i].sizes().y(), 2 * 1.8 * 150 / (4.0 / 3.0), 1e-9);
  }
}

TEST(FollowCamera, KeepsTheGroundAFifthUpAndTheBodyInView) {
  std::vector<FollowMoment> moments;
  for (int i = 0; i <= 60; ++i) moments.push_back({i / 30.0, Table(0, 0), 0.0});  // standing on y = 0
  const std::vector<Eigen::AlignedBox2d> resting = FollowBoxes(moments, {});
  for (const Eigen::AlignedBox2d& b : resting) EXPECT_NEAR((0.0 - b.min().y()) / b.sizes().y(), 0.2, 1e-12);
  // far above the ground: the body stays below the top fifth (the overlay's) instead
  for (FollowMoment& m : moments) m.body = Table(0, 900);
  for (const Eigen::AlignedBox2d& b : FollowBoxes(moments, {})) {
    EXPECT_NEAR((b.max().y() - 1000) / b.sizes().y(), 0.2, 1e-12);
    EXPECT_TRUE(b.contains(moments[0].body));
  }
}

// Off a cliff: the ground under the body drops by 300 in one frame; the camera eases down over
// several frames (no frame moves it by more than a quarter of the drop).
TEST(FollowCamera, EasesAJumpOfTheGroundUnderTheBody) {
  std::vector<FollowMoment> moments;
  for (int i = 0; i <= 60; ++i) moments.push_back({i / 30.0, Table(0, 300), i < 30 ? 300.0 : 0.0});
  const std::vector<Eigen::AlignedBox2d> boxes = FollowBoxes(moments, {});
  double largest = 0;
  for (size_t i = 1; i < boxes.size(); ++i)
    largest = std::max(largest, std::abs(boxes[i].center().y() - boxes[i - 1].center().y()));
  EXPECT_GT(largest, 0.0);
  EXPECT_LT(largest, 0.25 * 300);
  for (size_t i = 0; i < boxes.size(); ++i) EXPECT_TRUE(boxes[i].contains(moments[i].body)) << i;
}

// 3D: cubes of one size, centred on a body moving at constant velocity in x and z (exactly,
// first and last too), with the ground under it a fifth up when the body stands on it.
TEST(FollowCamera, FollowsA3DBodyInCubesOfOneSizeWithTheGroundInView) {
  std::vector<FollowMomentN<3>> moments;
  auto pot = [](double x, double y, double z) {
    return Eigen::AlignedBox3d(Eigen::Vector3d(x - 40, y, z - 40), Eigen::Vector3d(x + 40, y + 100, z + 40));
  };
  for (int i = 0; i <= 90; ++i) {
    const double t = i / 30.0;
    moments.push_back({t, pot(-100 + 60 * t, 20 - 5 * t, 30 * t), 20 - 5 * t});  // on a ground going down
  }
  const std::vector<Eigen::AlignedBox3d> boxes = FollowBoxes(moments, {});
  ASSERT_EQ(boxes.size(), moments.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_NEAR(boxes[i].center().x(), moments[i].body.center().x(), 1e-9) << i;
    EXPECT_NEAR(boxes[i].center().z(), moments[i].body.center().z(), 1e-9) << i;
    EXPECT_TRUE(boxes[i].sizes().isApprox(Eigen::Vector3d::Constant(2 * 1.8 * 50), 1e-12));  // half-extent 50
    EXPECT_NEAR((*moments[i].ground_height - boxes[i].min().y()) / boxes[i].sizes().y(), 0.2, 1e-9) << i;
    EXPECT_TRUE(boxes[i].contains(moments[i].body)) << i;
  }
}

}  // namespace
}  // namespace wobble::pipelines
