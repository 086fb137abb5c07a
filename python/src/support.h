// What the bindings share (support.cc): raising a stopped world as a Python exception, and
// running C++ loops with the GIL released while still answering Ctrl-C.
#pragma once

#include <chrono>
#include <future>

#include "bindings.h"
#include "wobble/core/interrupt.h"
#include "wobble/world/world.h"

namespace wobble::python {

// A body index the world has (InputError otherwise).
void CheckIndex(const World& w, int body);
// A material point: mass point k, or u (FFD bodies: lattice (s, t); linear bodies: undeformed
// coordinates); the world checks both.
MaterialPoint PointOf(const World& w, int body, const py::object& mass_point, const py::object& u);

// Raises wobble.SimulationStopped for a stopped world, with .cause, .step, .time and .body.
[[noreturn]] void RaiseStopped(const WorldStatus& status);

// Whether the call should stop for Ctrl-C: the library's flag (core/interrupt.h) is up, or, on
// Python's main thread, Python's signal handlers (run here with the GIL) raised
// KeyboardInterrupt, which is cleared and raises the flag for every worker. Call it every few
// thousand steps, without the GIL; the caller clears the flag when its call ends.
bool CtrlCPressed();

// Steps `world` until its time reaches t_end (to half a step) or `steps` more steps were taken
// (whichever comes first; steps < 0: no count), with the GIL released; raises
// SimulationStopped when the world stops and KeyboardInterrupt on Ctrl-C (the world keeps the
// state it reached).
void RunWorld(World& world, double t_end, long steps);

// Runs f (which must not touch Python) on a worker thread while the calling thread waits
// without the GIL, taking it every 50 ms to run Python's signal handlers: Ctrl-C raises the
// library's own flag (core/interrupt.h), which anneal, cmaes and the fits poll between
// iterations and batches. f's result or exception comes back here.
template <class F> auto WithCtrlC(F&& f) -> decltype(f()) {
  ClearInterrupt();
  auto done = std::async(std::launch::async, std::forward<F>(f));
  for (;;) {
    bool finished;
    {
      py::gil_scoped_release release;
      finished = done.wait_for(std::chrono::milliseconds(50)) == std::future_status::ready;
    }
    if (finished) break;
    if (PyErr_CheckSignals() != 0) {
      PyErr_Clear();
      RequestInterrupt();
    }
  }
  struct Clear {
    ~Clear() { ClearInterrupt(); }
  } clear;
  return done.get();
}

}  // namespace wobble::python
