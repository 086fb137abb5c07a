// VTK sources that turn one body of a wobble::World into vtkPolyData, in world coordinates
// (z = 0: wobble is 2D). Each is a vtkPolyDataAlgorithm with no input: set the world and the
// body, and call Modified() after the world has stepped so that the next Update() redraws.
//
//   LatticeSource    deformed control lattice: control points (vertices) and grid lines;
//                    point arrays rest_position (body frame) and displacement (body frame,
//                    Σ γ_d d^d_ij of Eq. 4.2: the deformation alone, without the rigid motion)
//   MassPointSource  mass points as vertices; arrays mass, velocity, applied_force (gravity
//                    plus the ground's penalty force of Eq. 4.24/4.25, world frame) and
//                    in_contact (1 for a point tied to the ground)
//   ShapeSource      the drawing polylines, resampled finer than the mass points: each segment
//                    is cut into SamplesPerSegment pieces and every sample is moved by the FFD
//                    (the thesis simulates few points and draws many, §4.10)
//   GroundSource     the ground line with its slope, as a filled band of given length and depth
//   SpringSource     the world's springs as lines anchor → held point; array stretch
//   TrailSource      trajectories of chosen points (lattice coordinates): call Record() after
//                    each frame; polylines with a point array time
#pragma once

#include <Eigen/Core>
#include <vector>
#include <vtkPolyDataAlgorithm.h>

#include "wobble/world/world.h"

namespace wobble::pipelines {

// What every source shares: the world and which body of it.
class WorldSourceBase : public vtkPolyDataAlgorithm {
 public:
  vtkTypeMacro(WorldSourceBase, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  // The world is not owned; it must outlive the source's updates.
  void SetWorld(const World* world) {
    world_ = world;
    Modified();
  }
  const World* GetWorld() const { return world_; }
  vtkSetMacro(Body, int);
  vtkGetMacro(Body, int);

 protected:
  WorldSourceBase() { SetNumberOfInputPorts(0); }
  // Reports (vtkErrorMacro) and returns false when there is no world or no such body.
  bool CheckWorld();
  const World* world_ = nullptr;
  int Body = 0;
};

class LatticeSource : public WorldSourceBase {
 public:
  static LatticeSource* New();
  vtkTypeMacro(LatticeSource, WorldSourceBase);

 protected:
  LatticeSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
};

class MassPointSource : public WorldSourceBase {
 public:
  static MassPointSource* New();
  vtkTypeMacro(MassPointSource, WorldSourceBase);

 protected:
  MassPointSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
};

class ShapeSource : public WorldSourceBase {
 public:
  static ShapeSource* New();
  vtkTypeMacro(ShapeSource, WorldSourceBase);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  // Pieces each drawing segment is cut into (>= 1).
  vtkSetClampMacro(SamplesPerSegment, int, 1, 100000);
  vtkGetMacro(SamplesPerSegment, int);

  // Lattice coordinates of every sample, in output order (one polyline after the other).
  std::vector<Eigen::Vector2d> SampleLatticeCoords() const;

 protected:
  ShapeSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int SamplesPerSegment = 16;

 private:
  // b0 and B of every sample (BodyModel::LocalBasis), cached per body and sample count:
  // the lattice weights of a sample never change, only q does.
  void UpdateCache();
  const BodyModel* cached_body_ = nullptr;
  int cached_samples_ = -1;
  std::vector<Eigen::Vector2d> sample_st_, sample_b0_;
  std::vector<Mat2D<double>> sample_B_;
  std::vector<std::pair<int, bool>> polyline_sizes_;  // samples per polyline, closed
};

class GroundSource : public WorldSourceBase {
 public:
  static GroundSource* New();
  vtkTypeMacro(GroundSource, WorldSourceBase);
  void PrintSelf(ostream& os, vtkIndent indent) override;
  // The band is centred on the ground point nearest Center, Length along the ground and
  // Depth below it.
  vtkSetVector2Macro(Center, double);
  vtkGetVector2Macro(Center, double);
  vtkSetMacro(Length, double);
  vtkGetMacro(Length, double);
  vtkSetMacro(Depth, double);
  vtkGetMacro(Depth, double);

 protected:
  GroundSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  double Center[2] = {0, 0};
  double Length = 2000.0, Depth = 100.0;
};

class SpringSource : public WorldSourceBase {
 public:
  static SpringSource* New();
  vtkTypeMacro(SpringSource, WorldSourceBase);

 protected:
  SpringSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
};

class TrailSource : public WorldSourceBase {
 public:
  static TrailSource* New();
  vtkTypeMacro(TrailSource, WorldSourceBase);
  // The points to follow, by lattice coordinates (s, t); clears the history.
  void SetTrackedPoints(const std::vector<Eigen::Vector2d>& lattice_coords);
  // Appends the tracked points' current world positions at the world's time.
  void Record();
  void ClearHistory();
  int GetNumberOfSamples() const { return int(times_.size()); }

 protected:
  TrailSource() = default;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

 private:
  std::vector<Eigen::Vector2d> tracked_;
  std::vector<double> times_;
  std::vector<std::vector<Eigen::Vector2d>> history_;  // [sample][tracked point]
};

// World position of lattice coordinates st of body `body` at the world's current state
// (Eq. 4.2 through BodyModel::LocalBasis).
Eigen::Vector2d WorldPositionOf(const World& world, int body, const Eigen::Vector2d& st);

}  // namespace wobble::pipelines
