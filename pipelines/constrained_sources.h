// VTK sources for the linear-deformation bodies of a World (Witkin & Welch 1990),
// 2D (z = 0) or 3D, in world coordinates; the FFD bodies of the same world are drawn by the
// sources of world_sources.h on World::ffd_world(). Like those, each is a
// vtkPolyDataAlgorithm with no input: set the world and the body, call Modified() after the
// world has changed.
//
//   LinearBoxSource        the body's "control box": a grid of lines over the box its mass
//                          points span (3 lines per direction and face), sampled finely and
//                          carried by x = R p(u), so a quadratic body's bend shows; the grid's
//                          nodes as vertices; point array rest_position (u)
//   LinearMassPointSource  the mass points x_k = R p(u_k) as vertices; arrays mass, velocity
//   LinearShapeSource      a LinearDrawing (polylines and, in 3D, a triangle surface) carried
//                          by x = R p(u)
//   AnchorSource           named points (material points of any body, fixed places) as
//                          vertices, e.g. the control points of a script
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>
#include <vtkPolyDataAlgorithm.h>

#include "wobble/body/linear_shapes.h"
#include "wobble/world/world.h"

namespace wobble::pipelines {

class ConstrainedSourceBase : public vtkPolyDataAlgorithm {
 public:
  vtkTypeMacro(ConstrainedSourceBase, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  // Not owned; must outlive the updates.
  void SetWorld(const World* world) {
    world_ = world;
    Modified();
  }
  vtkSetMacro(Body, int);
  vtkGetMacro(Body, int);

 protected:
  ConstrainedSourceBase() { SetNumberOfInputPorts(0); }
  // Reports and returns false without a world or when Body is not a linear body of it.
  bool CheckLinearBody();
  const World* world_ = nullptr;
  int Body = 0;
};

class LinearBoxSource : public ConstrainedSourceBase {
 public:
  static LinearBoxSource* New();
  vtkTypeMacro(LinearBoxSource, ConstrainedSourceBase);
  // Pieces each grid line is cut into (>= 1).
  vtkSetClampMacro(Pieces, int, 1, 10000);
  vtkGetMacro(Pieces, int);

 protected:
  LinearBoxSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int Pieces = 12;
};

class LinearMassPointSource : public ConstrainedSourceBase {
 public:
  static LinearMassPointSource* New();
  vtkTypeMacro(LinearMassPointSource, ConstrainedSourceBase);

 protected:
  LinearMassPointSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
};

class LinearShapeSource : public ConstrainedSourceBase {
 public:
  static LinearShapeSource* New();
  vtkTypeMacro(LinearShapeSource, ConstrainedSourceBase);
  void SetDrawing(const LinearDrawing& drawing) {
    drawing_ = drawing;
    Modified();
  }
  // Which part: lines (polylines), surface (triangles) or both (default).
  vtkSetMacro(Lines, bool);
  vtkSetMacro(Surface, bool);

 protected:
  LinearShapeSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  LinearDrawing drawing_;
  bool Lines = true, Surface = true;
};

class AnchorSource : public ConstrainedSourceBase {
 public:
  static AnchorSource* New();
  vtkTypeMacro(AnchorSource, ConstrainedSourceBase);
  struct Anchor {
    std::string name;
    MaterialPoint point;    // body < 0: a fixed place
    Eigen::VectorXd place;  // the fixed place
  };
  void SetAnchors(std::vector<Anchor> anchors) {
    anchors_ = std::move(anchors);
    Modified();
  }

 protected:
  AnchorSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  std::vector<Anchor> anchors_;
};

// World position of undeformed point u of linear body `body` (x = R p(u)) as 3 numbers (z = 0 in 2D).
Eigen::Vector3d LinearWorldPoint(const World& world, int body, const Eigen::VectorXd& u);

// A box holding every point of the body now: its mass points and the corners of its drawing's
// sampled points (a quadratic deformation can bulge beyond the mass points' hull, so the
// drawing's own samples are included when given).
Eigen::AlignedBox3d LinearBodyBounds(const World& world, int body, const LinearDrawing* drawing = nullptr);

}  // namespace wobble::pipelines
