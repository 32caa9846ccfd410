# cmake -DIN=file.spv -DOUT=file.cpp -DNAME=symbol -P embed_spirv.cmake: writes the SPIR-V words of
# IN as `extern const uint32_t vff::vk::detail::NAME[]` and NAME##Words, so that the library needs
# no shader file at run time. Words, not bytes: vkCreateShaderModule wants 4-byte aligned code.
# SPIR-V is little-endian on every host this project builds for, as is the word order below.
file(READ "${IN}" hex HEX)
string(LENGTH "${hex}" len)
math(EXPR rem "${len} % 8")
if(NOT rem EQUAL 0)
  message(FATAL_ERROR "${IN} is not a whole number of 32-bit words")
endif()
# Each word's four bytes, reversed into one hex literal.
string(REGEX REPLACE "([0-9a-f][0-9a-f])([0-9a-f][0-9a-f])([0-9a-f][0-9a-f])([0-9a-f][0-9a-f])"
       "0x\\4\\3\\2\\1u," words "${hex}")
string(REGEX REPLACE "((0x[0-9a-f]+u,){8})" "\\1\n" words "${words}")
math(EXPR count "${len} / 8")
file(WRITE "${OUT}" "// Generated from ${IN} by gpu/vulkan/embed_spirv.cmake.\n#include <cstddef>\n#include <cstdint>\nnamespace vff::vk::detail {\nextern const uint32_t ${NAME}[];\nextern const size_t ${NAME}Words;\nconst uint32_t ${NAME}[] = {\n${words}};\nconst size_t ${NAME}Words = ${count};\n}  // namespace vff::vk::detail\n")
