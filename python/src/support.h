// What the bindings share (support.cc): raising a stopped world as a Python exception, and
// running C++ loops with the GIL released while still answering Ctrl-C.
#pragma once

#include "bindings.h"
#include "wobble/world/world.h"

namespace wobble::python {

// Raises wobble.SimulationStopped for a stopped world, with .cause, .step, .time and .body.
[[noreturn]] void RaiseStopped(const WorldStatus& status);

// On Python's main thread: takes the GIL and runs Python's signal handlers; true when one
// raised (Ctrl-C: KeyboardInterrupt), whose error is then cleared for the caller to raise its
// own. Elsewhere (worker threads): false. Call it every few thousand steps, without the GIL.
bool CtrlCPressed();

// Steps `world` until its time reaches t_end (to half a step) or `steps` more steps were taken
// (whichever comes first; steps < 0: no count), with the GIL released; raises
// SimulationStopped when the world stops and KeyboardInterrupt on Ctrl-C (the world keeps the
// state it reached).
void RunWorld(World& world, double t_end, long steps);

}  // namespace wobble::python
