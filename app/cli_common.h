// What the `wobble` subcommands share: loading a body from an object file and mode files,
// parsing vectors given on the command line, and turning the ground/gravity flags into
// WorldParams. Everything that can be wrong with user input ends as a UsageError (exit 2).
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/core/errors.h"
#include "wobble/core/limits.h"
#include "wobble/world/world.h"

namespace wobble::app {

// Exit codes of the command.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;     // anything unexpected
constexpr int kExitBadInput = 2;    // a bad file or a bad command-line value
constexpr int kExitSimStopped = 3;  // the world stopped with a status (numerical trouble)
constexpr int kExitInterrupted = 130;  // Ctrl-C (128 + SIGINT)

// A bad command-line value; what() is the whole message for people.
class UsageError : public InputError {
 public:
  using InputError::InputError;
};

// The object file and its mode files (`--modes a.def,b.def`: modes of all files, in order).
struct BodyFiles {
  std::string object;
  std::vector<std::string> modes;
};
void AddBodyFlags(CLI::App* cmd, BodyFiles* files);
// Reads the files through wobble::formats and builds the model. Throws formats::ParseError for a bad
// file and std::invalid_argument when the modes do not fit the object.
// With check_modes, the mode set is checked as it loads (analysis::CheckModeSet): warnings
// (nearly dependent modes, modes the mass cannot see) go to stderr, and a dependent set — M
// singular — is refused with std::invalid_argument. Dim is the object file's dimension
// (formats::ObjectFileDimension: 3 for 'dimension 3' and 3D deformation files).
template <int Dim> std::shared_ptr<const BodyModelN<Dim>> LoadBody(const BodyFiles& files, bool check_modes = true);

// Gravity and ground flags, shared by simulate and inspect.
struct WorldFlags {
  bool no_gravity = false;
  bool no_ground = false;
  double ground_height = 0.0;
  double ground_slope_deg = 0.0;
  double ground_stiffness = Ground().stiffness;
  double ground_damping = Ground().normal_damping;
  double friction_damping = Ground().friction_damping;
  double friction_cap = Ground().friction_cap;
  std::string terrain;  // "X1 Y1 X2 Y2 ...": a terrain profile in place of the line (2D)
  std::vector<std::string> terrain_faces;  // "SEGMENT NAME VALUE ..": a segment's own constants
  std::string heightfield;  // a heightfield file: the 3D ground in place of the plane
};
void AddWorldFlags(CLI::App* cmd, WorldFlags* flags);
// Validates the flags (finite, non-negative where it matters) and fills the params.
WorldParams MakeWorldParams(const WorldFlags& flags);

// A fit's progress: a one-line "iteration N, cost C" on stderr when it is a terminal (an
// empty function otherwise), and the line's end.
std::function<void(int, double)> IterationLine();
void EndIterationLine();

// --max-steps and --max-record-mb (core/limits.h): what one command may simulate and keep.
void AddLimitFlags(CLI::App* cmd, Limits* limits);
// The flags themselves: --max-steps in [1, kMaxStepsLimit], --max-record-mb positive.
void CheckLimitFlags(const Limits& limits);
// The steps of a run of --duration at --dt within limits.max_steps, with a record of every
// `every`-th step of `columns` values within limits.max_record_mb (LimitExceeded otherwise,
// naming the flag that raises it).
long CheckRunLimits(double duration, double dt, long every, int columns, const Limits& limits);

// Parses a generalized-coordinate vector given as "1 2.5 -3" (spaces and/or commas) with
// one number per coordinate of the body (CoordinateNames). `what` names the flag in messages.
// An empty text gives zeros. Throws UsageError on a non-number, a non-finite number or a
// wrong count. ParseVelocities: the same for a velocity (VelocityNames).
template <int Dim>
Eigen::VectorXd ParseCoordinates(const std::string& text, const std::string& what, const BodyModelN<Dim>& body);
template <int Dim>
Eigen::VectorXd ParseVelocities(const std::string& text, const std::string& what, const BodyModelN<Dim>& body);

// What simulate, render, inspect and condition time start from: the body of the files, its
// start state (--q, --qdot; empty texts give rest) and the world options of the flags.
// A 3D object file (`dimension 3`) gives a 3D FFD body instead: --q is "tx ty tz rx ry rz g1 ..
// gD" (r a rotation vector: the turn by |r| radians about r), --qdot "vx vy vz wx wy wz dg1 ..
// dgD" (ω in the body frame), and the ground is the plane through y = --ground-height tilted
// by --ground-slope about z.
struct StartingWorld {
  // The body, of the object file's dimension (null for the other one).
  template <int Dim> const std::shared_ptr<const BodyModelN<Dim>>& body() const { return std::get<Dim - 2>(bodies); }
  int dim() const { return body<3>() ? 3 : 2; }
  // f(body) on the body of either dimension.
  template <class F> decltype(auto) OnBody(F&& f) const { return dim() == 3 ? f(*body<3>()) : f(*body<2>()); }
  std::tuple<std::shared_ptr<const BodyModel>, std::shared_ptr<const BodyModelN<3>>> bodies;  // one is set
  Eigen::VectorXd q0, qd0;
  WorldOptions options;
  World MakeWorld() const;  // the body alone in a world, at (q0, q̇0)
};
StartingWorld LoadStartingWorld(const BodyFiles& files, const std::string& q, const std::string& qdot,
                                const WorldFlags& flags, Integrator integrator, double dt);

// --integrator NAME; a UsageError listing the known names otherwise.
Integrator ParseIntegratorFlag(const std::string& name);

// The help of --q, --qdot and --integrator for the subcommands that start a body through
// LoadStartingWorld: both layouts, 2D and 3D, and every name ParseIntegrator takes (made from
// IntegratorNames(), so the help cannot fall behind the parser). `default_text` ends each one,
// e.g. "default: zeros".
std::string StateFlagHelp(const std::string& default_text);
std::string VelocityFlagHelp(const std::string& default_text);
std::string IntegratorFlagHelp();

// The names of --q and --qdot in messages: "tx ty theta g1 .. gD" for both of a 2D body (q̇ is
// dq/dt); "tx ty tz rx ry rz g1 .." and "vx vy vz wx wy wz dg1 .." for a 3D body.
template <int Dim> std::string CoordinateNames(const BodyModelN<Dim>& body);
template <int Dim> std::string VelocityNames(const BodyModelN<Dim>& body);
// The words of a list separated by commas and/or white space.
std::vector<std::string> ListWords(const std::string& text);
// Every word of such a list as a finite number (a UsageError naming `flag` otherwise).
std::vector<double> ParseNumbers(const std::string& text, const std::string& flag);
// Parses `expected_size` numbers (names: what they are, for messages); empty text gives zeros.
Eigen::VectorXd ParseNumbers(const std::string& text, const std::string& what, int expected_size,
                             const std::string& names, const std::string& body_name);

// An output folder that can be written (made if missing): a UsageError (exit 2) before any work
// otherwise, the same for every subcommand.
void CheckOutputFolder(const std::string& folder);
// The same for an output file given by `flag` (nothing to check when `path` is empty): its
// folder is made, it must be a regular file or absent, and its temporary file no FIFO.
void CheckOutputFile(const std::string& flag, const std::string& path);

// Requires a finite number, optionally positive or non-negative.
void RequireFinite(double value, const std::string& what);
void RequirePositive(double value, const std::string& what);
void RequireNonNegative(double value, const std::string& what);

}  // namespace wobble::app
