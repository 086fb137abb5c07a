// Render regression against baseline PNGs in tests/baselines, shared by the render tests
// (pipelines_render_test, pipelines_view_test). The comparison is described at the top of
// pipelines_render_test.cc: a pixel matches when some pixel of the other image within +-1 px
// has every channel within kChannelTolerance, checked both ways; at most kMaxBadFraction of
// the pixels may fail. WOBBLE_UPDATE_BASELINES=1 rewrites the baselines instead.
#pragma once

#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkPNGReader.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "pipelines/exports.h"
#include "pipelines/scene_view.h"
#include "support/source_paths.h"

namespace wobble::pipelines::testing_render {

namespace fs = std::filesystem;

constexpr int kChannelTolerance = 24;     // of 255, per channel
constexpr double kMaxBadFraction = 0.001;  // of the pixels

inline bool PixelNear(vtkImageData* a, int x, int y, vtkImageData* b, int comps) {
  int dims[3];
  b->GetDimensions(dims);
  const auto* pa = static_cast<const unsigned char*>(a->GetScalarPointer(x, y, 0));
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int bx = x + dx, by = y + dy;
      if (bx < 0 || by < 0 || bx >= dims[0] || by >= dims[1]) continue;
      const auto* pb = static_cast<const unsigned char*>(b->GetScalarPointer(bx, by, 0));
      bool all = true;
      for (int c = 0; c < comps && all; ++c) all = std::abs(int(pa[c]) - int(pb[c])) <= kChannelTolerance;
      if (all) return true;
    }
  return false;
}

inline void CompareWithBaseline(const std::string& name, vtkImageData* image) {
  const std::string baseline_path = wobble::test_env::BaselineDir() + "/" + name + ".png";
  if (const char* update = std::getenv("WOBBLE_UPDATE_BASELINES"); update && std::string(update) == "1") {
    WritePng(baseline_path, image, 9);
    std::cout << "wrote baseline " << baseline_path << "\n";
    return;
  }
  ASSERT_TRUE(fs::exists(baseline_path)) << baseline_path << " is missing: run with WOBBLE_UPDATE_BASELINES=1";
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName(baseline_path.c_str());
  reader->Update();
  vtkImageData* base = reader->GetOutput();
  int dn[3], db[3];
  image->GetDimensions(dn);
  base->GetDimensions(db);
  const int comps = image->GetNumberOfScalarComponents();
  ASSERT_EQ(dn[0], db[0]);
  ASSERT_EQ(dn[1], db[1]);
  ASSERT_EQ(comps, base->GetNumberOfScalarComponents());
  long bad = 0;
  auto diff = vtkSmartPointer<vtkImageData>::New();
  diff->SetDimensions(dn[0], dn[1], 1);
  diff->AllocateScalars(VTK_UNSIGNED_CHAR, comps);
  for (int y = 0; y < dn[1]; ++y)
    for (int x = 0; x < dn[0]; ++x) {
      const bool ok = PixelNear(image, x, y, base, comps) && PixelNear(base, x, y, image, comps);
      bad += ok ? 0 : 1;
      const auto* pn = static_cast<const unsigned char*>(image->GetScalarPointer(x, y, 0));
      const auto* pb = static_cast<const unsigned char*>(base->GetScalarPointer(x, y, 0));
      auto* pd = static_cast<unsigned char*>(diff->GetScalarPointer(x, y, 0));
      for (int c = 0; c < comps; ++c) pd[c] = (unsigned char)std::min(255, 4 * std::abs(int(pn[c]) - int(pb[c])));
    }
  const double fraction = double(bad) / (double(dn[0]) * dn[1]);
  if (fraction > kMaxBadFraction) {
    const std::string out = wobble::test_env::RenderFailureDir();
    WritePng(out + "/" + name + "_new.png", image);
    WritePng(out + "/" + name + "_diff.png", diff);
    ADD_FAILURE() << name << ": " << bad << " pixels (" << 100 * fraction << "%) differ from " << baseline_path
                  << " by more than " << kChannelTolerance << " within +-1 px; new image and diff in " << out;
  }
}

}  // namespace wobble::pipelines::testing_render
