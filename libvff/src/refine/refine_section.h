// refine_section.h - the REFN section's bytes (private): spec/format.md section 14. The reader's
// and validator's parser and the writer share these.
#pragma once

#include <cstdint>
#include <span>

#include "vff/error.h"
#include "vff/refine.h"

namespace vff::detail {

// Bytes of the unsure bits of a field (ceil(mapCount * M * M / 8)).
uint64_t refineUnsureBytes(const FieldDesc& field) noexcept;

// Checks raw REFN bytes against the field (rules 8501-8503, in order; the first problem found) and
// fills *out with views into `raw`, which must be 4-byte aligned. Errors carry the offset inside
// the section (the caller adds the section's) and tag REFN.
Status parseRefinement(const FieldDesc& field, std::span<const uint8_t> raw, RefinementView* out);

}  // namespace vff::detail
