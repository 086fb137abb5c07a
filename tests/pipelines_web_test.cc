// The web preview's folder (pipelines/web_preview.h) without a browser: its files, the model's
// base64, the page's filled-in title, and the error that names libjs-three when three.js is
// missing. tests/cli/check_web_preview.py opens the page in Chromium.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "pipelines/trajectory_render.h"
#include "pipelines/web_preview.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void Write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// a folder laid out as libjs-three's /usr/share/javascript/three, with stand-in files
fs::path FakeThreeJs(const fs::path& root) {
  Write(root / "three.min.js", "// three\n");
  Write(root / "examples/js/loaders/GLTFLoader.js", "// loader\n");
  Write(root / "examples/js/controls/OrbitControls.js", "// controls\n");
  return root;
}

TEST(WebPreview, Base64IsRfc4648) {  // the RFC's own test vectors, padding included
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64(std::string("\0\xff\xfe", 3)), "AP/+");  // bytes above 127 and zero
}

TEST(WebPreview, PageHasTheTitleEscapedAndTheGlbName) {
  const std::string html = WebPreviewHtml("a<b & \"c\"", "run.glb");
  EXPECT_NE(html.find("<title>a&lt;b &amp; &quot;c&quot; · wobble</title>"), std::string::npos);
  EXPECT_NE(html.find("href=\"run.glb\""), std::string::npos);
  EXPECT_EQ(html.find("@WOBBLE_"), std::string::npos);  // every placeholder filled
  // the page's scripts are the folder's own: nothing from the network
  for (const char* script : {"three/three.min.js", "three/GLTFLoader.js", "three/OrbitControls.js", "model.js"})
    EXPECT_NE(html.find(std::string("<script src=\"") + script + "\">"), std::string::npos) << script;
  EXPECT_EQ(html.find("http"), std::string::npos);
}

TEST(WebPreview, WritesTheFolder) {
  const fs::path dir = fs::path(testing::TempDir()) / "wobble_web_preview";
  fs::remove_all(dir);
  const std::string glb("glTF\x02\0\0\0bytes", 13);
  const std::vector<std::string> written =
      WriteWebPreview((dir / "web").string(), "pot3", glb, "pot3", FakeThreeJs(dir / "three").string());
  ASSERT_EQ(written.size(), 6u);
  EXPECT_EQ(written[0], (dir / "web" / "index.html").string());
  EXPECT_EQ(Read(dir / "web" / "pot3.glb"), glb);
  EXPECT_EQ(Read(dir / "web" / "model.js"), "window.wobbleGlbBase64 =\n\"" + Base64(glb) + "\";\n");
  EXPECT_EQ(Read(dir / "web" / "three" / "GLTFLoader.js"), "// loader\n");
  EXPECT_EQ(Read(dir / "web" / "three" / "OrbitControls.js"), "// controls\n");
  EXPECT_EQ(Read(dir / "web" / "three" / "three.min.js"), "// three\n");
  for (const auto& entry : fs::recursive_directory_iterator(dir / "web"))
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();  // written atomically, nothing left over
  fs::remove_all(dir);
}

TEST(WebPreview, MissingThreeJsNamesThePackage) {
  const fs::path dir = fs::path(testing::TempDir()) / "wobble_web_no_three";
  fs::remove_all(dir);
  try {
    WriteWebPreview((dir / "web").string(), "run", "glb", "run", (dir / "nowhere").string());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("libjs-three"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("three.min.js"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "web" / "index.html"));  // checked before anything is written
  fs::remove_all(dir);
}

TEST(WebPreview, WebImpliesTheGltf) {
  RenderOutputs out;
  ASSERT_EQ(SetOutputs({"web"}, &out), "");
  EXPECT_TRUE(out.web);
  EXPECT_TRUE(out.gltf);
  EXPECT_FALSE(out.frames);
  EXPECT_TRUE(KeepWithoutDisplay(&out).empty());  // needs no display
  EXPECT_TRUE(out.web);
  EXPECT_NE(SetOutputs({"html"}, &out).find("web"), std::string::npos);  // the message lists it
}

}  // namespace
}  // namespace wobble::pipelines
