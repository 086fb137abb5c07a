// A web preview of a recorded run: a folder that opens in a browser from the local disk (a
// double-click on index.html) and plays the run's glTF 2.0 animation (gltf_export.h) with
// three.js, nothing fetched from the network.
//
// Layout of `folder` (RenderTrajectory writes it as OUT/web/):
//   index.html          the page (pipelines/web/index.html, embedded in the binary at build time)
//   NAME.glb            the .glb, for people who want the file (the page does not read it)
//   model.js            the same bytes as a base64 string in a classic script: Chromium refuses
//                       fetch/XHR of file:// URLs, but loads <script src> from beside the page
//   three/three.min.js, three/GLTFLoader.js, three/OrbitControls.js
//                       copied from Debian's libjs-three (three.js r111), the non-module
//                       examples/js versions: ES modules do not load from file:// in Chromium
// The page plays the animation "run" (position, rotation, morph target weights) with orbit
// controls, a play/pause button and a time slider, from the glTF's "camera" node when there is
// one; window.wobbleReady (a promise) resolves when it has loaded, and window.wobbleSetTime(t)
// pauses at time t and renders synchronously (for tests). Around three.js r111's limits the page
// binds the animation's tracks by object (r111 binds by name, and a body's node and its first
// primitive share one), gives lines their morph targets, blends more than 8 targets itself,
// and builds an orthographic camera from the file's xmag/ymag (r111's loader halves them).
#pragma once

#include <string>
#include <vector>

namespace wobble::pipelines {

// Where Debian's libjs-three puts three.js.
inline constexpr const char* kThreeJsDir = "/usr/share/javascript/three";

// The three.js files the page loads: their paths under three_js_dir, and their names in the
// folder's three/. std::runtime_error naming the package when one of them is missing (checked
// before a long render, so it fails early).
void CheckThreeJs(const std::string& three_js_dir = kThreeJsDir);

// The page's text with `title` (HTML-escaped) and the .glb's file name filled in.
std::string WebPreviewHtml(const std::string& title, const std::string& glb_name);

// RFC 4648 base64 (with padding) of `bytes`, by FFmpeg's libavutil.
std::string Base64(const std::string& bytes);

// Writes the folder above (every file atomically); returns the paths written, index.html first.
// std::runtime_error naming the file on a failed write or a missing three.js file.
std::vector<std::string> WriteWebPreview(const std::string& folder, const std::string& name, const std::string& glb_bytes,
                                         const std::string& title, const std::string& three_js_dir = kThreeJsDir);

}  // namespace wobble::pipelines
