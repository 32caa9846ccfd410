// Fuzz target: the scene description reader (vff/scene_description.h, spec/scene.md) on arbitrary
// text. Whatever the bytes, parseSceneDescription returns a description or a scene error (an ID of
// spec/scene.md, 11xxx), its message naming the description. A description it accepts must survive the writer:
// formatSceneDescription gives text that parses again to an equal description and formats to the
// same bytes (the writer promises that equal descriptions give equal bytes).
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "vff/scene_description.h"

namespace {

constexpr const char* kName = "fuzz.vffscene.json";

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "scene round trip: %s\n%s\n", what, detail.c_str());
  std::abort();
}

// The same bits: a negative zero must come back negative (regressions/scene/negative-zero.json:
// the writer once wrote it "-0", the integer 0 to a JSON reader).
bool sameFloat(float a, float b) { return std::bit_cast<uint32_t>(a) == std::bit_cast<uint32_t>(b); }

bool equal(const vff::SceneDescription& a, const vff::SceneDescription& b) {
  if (a.generator != b.generator || a.extrasJson != b.extrasJson || a.fields.size() != b.fields.size() ||
      a.instances.size() != b.instances.size())
    return false;
  for (size_t i = 0; i < a.fields.size(); ++i) {
    const vff::SceneField &x = a.fields[i], &y = b.fields[i];
    if (x.uri != y.uri || x.name != y.name || x.sourceJson != y.sourceJson) return false;
  }
  for (size_t i = 0; i < a.instances.size(); ++i) {
    const vff::SceneInstance &x = a.instances[i], &y = b.instances[i];
    if (x.field != y.field || x.name != y.name || x.extrasJson != y.extrasJson || !sameFloat(x.scale, y.scale) ||
        !sameFloat(x.translation.x, y.translation.x) || !sameFloat(x.translation.y, y.translation.y) ||
        !sameFloat(x.translation.z, y.translation.z))
      return false;
    for (int c = 0; c < 4; ++c)
      if (!sameFloat(x.rotation[c], y.rotation[c])) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  vff::Result<vff::SceneDescription> a = vff::parseSceneDescription(text, kName);
  if (!a) {
    const vff::Error& e = a.error();
    if (uint32_t(e.code) / 1000 != uint32_t(vff::Code::kSceneJson) / 1000)
      fail("refused with a code that is not a scene error", e.toString());
    if (e.message.rfind(kName, 0) != 0) fail("the message does not start with the description's name", e.message);
    // (A message may quote the input, which may hold those words itself.)
    if (e.message.find("internal error") != std::string::npos && text.find("internal error") == std::string_view::npos)
      fail("an internal error", e.message);
    return 0;
  }
  vff::Result<std::string> t = vff::formatSceneDescription(*a);
  if (!t) fail("an accepted description does not format", t.error().toString());
  vff::Result<vff::SceneDescription> b = vff::parseSceneDescription(*t, kName);
  if (!b) fail("the formatted text does not parse", b.error().toString() + "\n" + *t);
  if (!equal(*a, *b)) fail("the formatted text reads back different", *t);
  vff::Result<std::string> t2 = vff::formatSceneDescription(*b);
  if (!t2) fail("a description read back does not format", t2.error().toString());
  if (*t2 != *t) fail("formatting again gives other bytes", *t);
  return 0;
}
