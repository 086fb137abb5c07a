#include "pipelines/viewer_loop.h"

#include "wobble/formats/line_reader.h"
#include "wobble/formats/parse_error.h"

#include <algorithm>
#include <sstream>
#include <vector>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <vtkCommand.h>
#include <vtkImageData.h>
#include <vtkInteractorEventRecorder.h>
#include <vtkInteractorStyleImage.h>
#include <vtkObjectFactory.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkWindowToImageFilter.h>

namespace wobble::pipelines {

template <class T> using Ptr = vtkSmartPointer<T>;

namespace {

// The mouse and the keys of both viewers (AttachViewerStyle); the timer draws frames. Middle/
// right buttons and the wheel keep vtkInteractorStyleImage's pan and zoom; its window-level
// (left button) and its keys are replaced.
class ViewerStyle : public vtkInteractorStyleImage {
 public:
  static ViewerStyle* New();
  vtkTypeMacro(ViewerStyle, vtkInteractorStyleImage);
  ViewerControls* view = nullptr;

  void OnLeftButtonDown() override {
    const int* p = GetInteractor()->GetEventPosition();
    dragging_ = view->BeginDrag(p[0], p[1]);
  }
  void OnLeftButtonUp() override {
    if (dragging_) view->EndDrag();
    dragging_ = false;
  }
  void OnMouseMove() override {
    if (dragging_) {
      const int* p = GetInteractor()->GetEventPosition();
      view->DragTo(p[0], p[1]);
      return;
    }
    vtkInteractorStyleImage::OnMouseMove();
  }
  void OnChar() override {
    const char code = GetInteractor()->GetKeyCode();
    if (code > 32 && code < 127) view->HandleKey(std::string(1, code));
    else if (code == ' ') view->HandleKey("space");
  }
  void OnKeyPress() override {
    const char* sym = GetInteractor()->GetKeySym();
    if (!sym) return;
    const std::string s = sym;
    if (s == "Escape" || s == "Left" || s == "Right") view->HandleKey(s);
  }
  void OnTimer() override { view->Frame(); }

 private:
  bool dragging_ = false;
};
vtkStandardNewMacro(ViewerStyle);

}  // namespace

double FramePacer::BeginFrame(double fps, bool fixed_frame_time) {
  const auto now = std::chrono::steady_clock::now();
  since_ = have_frame_ ? std::chrono::duration<double>(now - last_).count() : 1.0 / fps;
  if (!have_frame_) first_ = now;
  have_frame_ = true;
  last_ = now;
  return fixed_frame_time ? 1.0 / fps : std::min(since_, kMaxFrameTime);
}

void FramePacer::Played(double simulated) {
  stats.simulated += simulated;
  if (stats.frames > 0) stats.playing_wall += since_;
  ++stats.playing_frames;
}

bool FramePacer::EndFrame() {
  ++stats.frames;
  stats.wall = std::chrono::duration<double>(last_ - first_).count();
  return max_frames > 0 && stats.frames >= max_frames;
}

void AttachViewerStyle(vtkRenderWindowInteractor* interactor, ViewerControls* controls) {
  auto style = Ptr<ViewerStyle>::New();
  style->view = controls;
  interactor->SetInteractorStyle(style);  // the interactor keeps it
}

void CheckEventFile(const std::string& path) {
  formats::detail::WithFile(path, [&](std::istream& in) {
    double version = 1.0;  // a file without a StreamVersion line is read as 1.0
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      std::istringstream words(line);
      std::vector<std::string> w;
      for (std::string word; words >> word;) w.push_back(word);
      if (w.empty()) continue;
      if (w[0][0] == '#') {
        if (w.size() >= 3 && w[1] == "StreamVersion") {
          if (w[2] != "1" && w[2] != "1.0" && w[2] != "1.1")
            throw formats::ParseError(path, number, "StreamVersion " + w[2] + ": VTK 9.1 plays 1.0 and 1.1");
          version = std::stod(w[2]);
        }
        continue;
      }
      if (vtkCommand::GetEventIdFromString(w[0].c_str()) == vtkCommand::NoEvent)
        throw formats::ParseError(path, number, "'" + w[0] + "' is not a VTK event (e.g. TimerEvent, MouseMoveEvent, "
                                                "LeftButtonPressEvent, KeyPressEvent, CharEvent)");
      const bool v11 = version >= 1.1;
      const size_t values = v11 ? 6 : 7;
      if (w.size() != values + 1)
        throw formats::ParseError(
            path, number,
            std::string("StreamVersion ") + (v11 ? "1.1" : "1.0") + " lines are 'EventName X Y " +
                (v11 ? "modifiers" : "ctrl shift") + " keycode repeatCount keysym' (" + std::to_string(values) +
                " values after the name), got " + std::to_string(w.size() - 1) +
                (v11 ? " (1.1 has one modifiers mask: 1 shift, 2 control, 4 alt)" : ""));
      // all but the key symbol are whole numbers (the key code too: 107 for 'k')
      for (size_t i = 1; i + 1 < w.size(); ++i) {
        int v;
        const bool negative = !w[i].empty() && w[i][0] == '-';
        if (!formats::detail::ParseInt(negative ? w[i].substr(1) : w[i], &v))
          throw formats::ParseError(path, number, "expected a whole number, got '" + w[i] + "'");
      }
    }
    return 0;
  });
}

void RunViewerLoop(vtkRenderWindowInteractor* interactor, double fps, const FramePacer& pacer,
                   const std::string& events_file, bool keep_open) {
  if (!events_file.empty()) {
    CheckEventFile(events_file);  // VTK skips what it cannot read without a word
    auto recorder = Ptr<vtkInteractorEventRecorder>::New();
    recorder->SetInteractor(interactor);
    recorder->SetFileName(events_file.c_str());
    recorder->Play();
    recorder->Off();
    if (!keep_open) return;
  }
  if (pacer.max_frames > 0 && pacer.stats.frames >= pacer.max_frames) return;
  interactor->CreateRepeatingTimer(std::max(1UL, (unsigned long)std::lround(1000.0 / fps)));
  interactor->Start();
}

vtkSmartPointer<vtkImageData> CaptureWindow(vtkRenderWindow* window) {
  auto grab = Ptr<vtkWindowToImageFilter>::New();
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->ShouldRerenderOn();
  grab->Update();
  auto image = Ptr<vtkImageData>::New();
  image->DeepCopy(grab->GetOutput());
  return image;
}

}  // namespace wobble::pipelines
