// shard_edit: a copy of a .vff file with one META value set, for the --merge refusal tests
// (shard_tests.sh): parts that claim another version, range or codec, valid files otherwise.
//
//   vff_shard_edit IN OUT POINTER JSON
//       OUT: IN's field and maps (zstd level 1 blocks, IN's layout limits) with META's value at the
//       JSON pointer POINTER (e.g. /vff.partial/version) set to the JSON text JSON.
#include <nlohmann/json.hpp>

#include <cstdio>
#include <vector>

#include "vff/vff.h"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: vff_shard_edit IN OUT POINTER JSON\n");
    return 1;
  }
  auto f = vff::File::open(argv[1]);
  if (!f) {
    std::fprintf(stderr, "vff_shard_edit: %s\n", f.error().toString().c_str());
    return 1;
  }
  nlohmann::json meta = nlohmann::json::parse(f->metadata());
  meta[nlohmann::json::json_pointer(argv[3])] = nlohmann::json::parse(argv[4]);
  const vff::LayoutDesc& l = f->layout();
  vff::WriteOptions o;
  o.codec = vff::Codec::kZstd;
  o.zstdLevel = 1;
  o.sync = false;
  o.layout = vff::LayoutLimits{l.target, l.maxTextureSize, l.maxLayers, l.gutter};
  o.metadataJson = meta.dump();
  auto w = vff::Writer::create(argv[2], f->field(), o);
  vff::Status st = w ? vff::Status{} : vff::Status(w.error());
  for (vff::Plane p : {vff::Plane::kDistance, vff::Plane::kNormal}) {
    if (!st || !f->plane(p).present) continue;
    std::vector<uint8_t> block;
    for (uint32_t b = 0; st && b < f->plane(p).blocks.size(); ++b) {
      block.resize(f->plane(p).blocks[b].rawSize);
      st = f->decodeBlock(p, b, block);
      if (st) st = w->writeMaps(p, block);
    }
  }
  if (st) st = w->finish();
  if (!st) {
    std::fprintf(stderr, "vff_shard_edit: %s\n", st.error().toString().c_str());
    return 1;
  }
  return 0;
}
