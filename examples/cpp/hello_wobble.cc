// Hello, wobble: the Box2D-style first program. Loads the table of Fig. 1.2 with its four
// modes, drops it from 50 units onto the ground and prints where it comes to rest.
//   hello_wobble DATA_DIR    (the folder holding table.obj and table_modes.def)
#include <cstdio>
#include <exception>
#include <memory>
#include <string>

#include "wobble/body/body_model.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/world/world.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: hello_wobble DATA_DIR\n");
    return 2;
  }
  const std::string data = argv[1];
  try {
    auto table = std::make_shared<const wobble::BodyModel>(wobble::formats::ReadObjectFile(data + "/table.obj"),
                                                           wobble::formats::ReadDeformationFile(data + "/table_modes.def"));
    wobble::WorldOptions options;
    options.dt = 0.01;
    wobble::World world(options);
    const int body = world.AddBody(table);
    Eigen::VectorXd q = Eigen::VectorXd::Zero(table->num_q());
    q[1] = 50;  // ty: the legs' feet 50 above the ground
    world.SetState(body, q, Eigen::VectorXd::Zero(table->num_q()));

    // the table bounces and wobbles for a while (its modes are lightly damped): report every
    // 5 s until its kinetic energy has stayed below 1 at three whole seconds in a row (at rest),
    // or 120 s pass
    int calm_seconds = 0;
    for (int second = 1; second <= 120; ++second) {
      if (!world.RunUntil(second)) {
        std::fprintf(stderr, "hello_wobble: %s\n", world.status().message.c_str());
        return 3;
      }
      const Eigen::VectorXd& s = world.q(body);
      const double kinetic = world.KineticEnergy(body);
      calm_seconds = kinetic < 1.0 ? calm_seconds + 1 : 0;
      if (second % 5 == 0 || calm_seconds == 3)
        std::printf("t = %5.1f s   x = %8.3f   y = %8.3f   angle = %7.4f   kinetic energy = %10.3f\n", world.time(), s[0],
                    s[1], s[2], kinetic);
      if (calm_seconds == 3) {
        std::printf("at rest at y = %.3f after %ld steps\n", s[1], world.steps());
        return 0;
      }
    }
    std::printf("still moving after %ld steps\n", world.steps());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hello_wobble: %s\n", e.what());
    return 2;
  }
}
