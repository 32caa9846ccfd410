// Fuzz target: the validator and File::openMemory on arbitrary bytes, under every checksum policy.
// Whatever the bytes, both must return (a report, a File or an Error), never crash or hang, and
// agree: a file the validator finds free of errors must open.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "vff/vff.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> bytes(data, size);
  const vff::Report report = vff::validate(bytes);
  for (vff::ChecksumPolicy p : {vff::ChecksumPolicy::kVerifyAll, vff::ChecksumPolicy::kLazy, vff::ChecksumPolicy::kNone}) {
    vff::ReadOptions o;
    o.checksums = p;
    vff::Result<vff::File> f = vff::File::openMemory(bytes, o);
    if (p == vff::ChecksumPolicy::kVerifyAll && report.valid() && !f.ok()) std::abort();  // they must agree
    if (f.ok()) (void)f->field().mapCount;
  }
  return 0;
}
