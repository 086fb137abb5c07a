// PYBIND11_MODULE: the extension `wobble._wobble`; python/wobble/__init__.py re-exports it.
#include "bindings.h"

PYBIND11_MODULE(_wobble, m) {
  using namespace wobble::python;
  m.doc() =
      "wobble: soft, cartoon-like characters by dynamic free-form deformation (Faloutsos 1995)\n"
      "and Witkin & Welch (1990) linear bodies. The C++ library, from Python.";
  BindErrors(m);
  BindBodies(m);
  BindWorld(m);
  BindBehaviours(m);  // after World: a Controller
  BindRecord(m);
  BindRollout(m);
  BindScript(m);
  BindSynth(m);
  BindFit(m);
  BindGradients(m);
  BindAnalysis(m);
#ifdef WOBBLE_PYTHON_RENDER
  BindRender(m);
#endif
}
