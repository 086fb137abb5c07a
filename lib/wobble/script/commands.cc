// The command table: every command of the script language once, with its usage, its one-line
// help and its handler. README.md ("Scripts") documents each in full.
#include "wobble/script/internal/interpreter_internal.h"

namespace wobble::script {

const std::vector<Command>& CommandTable() {
  static const std::vector<Command> table = {
      // the FFD object of the thesis (§4.10.2, appendix C), its control and its runs
      {"load_obj", "load_obj FILE", "load an object file (lattice, mass points, drawing)", LoadObj},
      {"load_def", "load_def FILE [FILE...]", "load deformation files; their modes replace the current set", LoadDef},
      {"trans", "trans X Y THETA", "place the object: set_vec q is relative to this placement", Trans},
      {"set", "set NAME VALUE", "set a parameter (see Parameters)", Set},
      {"terrain", "terrain X1 Y1 X2 Y2 ... | terrain off",
       "the ground becomes a profile through these points, left to right, solid below (equal X: a cliff)", TerrainCommand},
      {"terrain_face", "terrain_face SEGMENT NAME VALUE [NAME VALUE ...]",
       "a terrain segment's own grconst, grdam, frconst or frsin (1-based, left to right)", TerrainFaceCommand},
      {"heightfield", "heightfield FILE | heightfield off",
       "3D objects stand on the heightfield y = h(x, z) in FILE ('origin X0 Z0', 'spacing DX DZ', a row of heights per "
       "z) in place of the ground plane; the ground's constants apply unless a region sets its own",
       HeightfieldCommand},
      {"heightfield_region", "heightfield_region X0 Z0 X1 Z1 NAME VALUE [NAME VALUE ...]",
       "the heightfield's cells whose centres lie in [X0, X1] x [Z0, Z1] get their own grconst, grdam, frconst or frsin",
       HeightfieldRegionCommand},
      {"assign", "assign MODE STIFFNESS DAMPING", "mode MODE (1-based or name): V = K g^2, force -c g'", Assign},
      {"mode", "mode MODE active|passive", "designate a mode active (PD-controlled) or passive", Mode},
      {"set_vec", "set_vec q|dq V1 .. Vn", "generalized coordinates or velocities, n = 3 + modes", SetVec},
      {"simul", "simul [DURATION]", "simulate from `time` to `end` (or for DURATION)", Simul},
      {"pose", "pose T1 .. Tk DURATION", "append a pose: one target per active mode, held for DURATION", Pose},
      {"key", "key TIME MODE=VALUE ...", "a keyframe at TIME (from the start of the keyframed run)", Key},
      {"schedule", "schedule FILE.csv | schedule off",
       "play per-step targets of every mode (`wobble fit spacetime --targets`) in every run from its start, in place "
       "of the pose graph; FILE as written, from the working directory",
       Schedule},
      {"hold", "hold S T | hold off", "hold the point at lattice coordinates (S, T) in place while keyframing (3D: hold S T U)", Hold},
      {"keyframe", "keyframe", "play the keys from the current state, then hand over to simulation", Keyframe},
      {"spring", "spring S T X Y [K [C [REST]]]",
       "a spring from lattice point (S, T) to the world point (X, Y); a 3D object's: spring S T U X Y Z [K [C [REST]]]",
       SpringCommand},
      {"clear", "clear poses|keys|springs|output|energy|track",
       "forget poses, keys, springs, recorded rows, energy or the runs render draws", Clear},
      {"output", "output FILE.csv [EVERY] | output off", "record the state of every EVERY-th step as CSV", Output},
      {"print", "print", "print the state, energies and the control energy", Print},
      {"anneal", "anneal ITERATIONS", "simulated annealing of the pose graph (Fig. 5.2)", Anneal},
      {"cmaes", "cmaes GENERATIONS", "CMA-ES (pagmo2) on the same problem as anneal; population = batch (>= 5)", Cmaes},
      {"gait", "gait SKIP CYCLES", "distance travelled per cycle of the pose graph, after SKIP cycles", Gait},
      {"save", "save FILE", "write a script that rebuilds the current setup and replays its controller", Save},
      {"render", "render DIR [WHAT] [NAME=VALUE ...]",
       "draw into DIR: with a scene (linear bodies) its recorded frames, WHAT a comma list of frames, filmstrip, vtp, "
       "mp4, webp, gltf, web (default frames,filmstrip,vtp; videos at the `record` rate); otherwise every FFD run since load_obj (or clear track), WHAT of frames, filmstrip, charts, vtp, "
       "exr, disp, mp4, webp, gltf, web (default frames,filmstrip,charts) and NAME=VALUE options of wobble render (size=WxH, fps=N, "
       "filmstrip=T1,T2,.., filmstrip-columns=N, filmstrip-cycle=K,PANELS, color-by=ARRAY, ...)",
       Render},
      {"echo", "echo TEXT", "print TEXT", Echo},
      // Witkin & Welch scenes (linear bodies, constraints, motion control, goal behaviours)
      {"linear",
       "linear NAME 2d|3d affine|quadratic box HX HY [HZ] | pyramid W H [grid N] [levels N] [mass M] [at X Y [Z]] [ke K] "
       "[kc K] [kd K] [kq K] [ground]",
       "a linear-deformation body x = R p(u) (a box or a pyramid of mass points), at rest at X Y Z; with 'ground' its "
       "mass points touch the ground (the set ground line or terrain; in 3D its plane)",
       Linear},
      {"ffd", "ffd NAME", "the loaded FFD object (its modes and state q, dq) joins the scene as body NAME", Ffd},
      {"point", "point NAME BODY U1 U2 [U3]",
       "name a material point of a body (undeformed coordinates; lattice S T of an FFD body)", PointCommand},
      {"place", "place NAME X Y [Z]", "name a fixed place in the world (a sky point)", Place},
      {"nail", "nail NAME POINT [X Y [Z]]", "nail a point where it is (or at X Y Z), now", Nail},
      {"attach", "attach NAME POINT_A POINT_B", "attach two points of bodies to each other, now", Attach},
      {"path", "path NAME 2d|3d T X Y [Z] T X Y [Z] ...", "keyframes of a control point: a C2 cubic spline through them",
       PathCommand},
      {"trajectory", "trajectory NAME POINT PATH [preroll DT]",
       "queue: the point follows PATH from its first key (preroll: a cubic from where it is)", TrajectoryCommand},
      {"impulse", "impulse POINT VX VY [VZ]", "queue: an impulse that gives the point this velocity (0: stop dead)",
       ImpulseCommand},
      {"chase", "chase POINT TARGET DURATION [VX VY [VZ]]",
       "queue: the point chases a point or place, meeting it after DURATION", ChaseOrGrab},
      {"connect", "connect POINT TARGET [NAME]", "queue: velocity-matching impulse, then attach (nail for a place)",
       ConnectCommand},
      {"grab", "grab POINT TARGET DURATION [VX VY [VZ]]", "queue: chase, then connect (constraint connect:POINT)",
       ChaseOrGrab},
      {"release", "release NAME", "queue: remove a constraint", ReleaseCommand},
      {"on", "on NAME", "queue: switch a constraint on (with an impulse that makes velocities legal)", OnOff},
      {"off", "off NAME", "queue: switch a constraint off (the point goes ballistic)", OnOff},
      {"wait", "wait DURATION", "queue: let DURATION pass before the next behaviour", WaitCommand},
      {"wait_for", "wait_for time T | near A B R | below A Y | above A Y", "queue: wait until the condition holds",
       WaitForCommand},
      {"record", "record FPS | record off", "record the scene's state FPS times per simulated second for render",
       RecordCommand},
      {"help", "help", "list the commands and the parameters of set", Help},
      {"quit", "quit", "stop (interactive use)", Quit},
  };
  return table;
}

}  // namespace wobble::script
