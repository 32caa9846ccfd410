# cmake -DIN=file -DOUT=file.cpp -P embed_text.cmake: writes IN's bytes as the NUL-terminated
# array vffx::gl::kPnanovdbText (sdf_block.cpp), so that the shader text needs no file at run time.
file(READ "${IN}" hex HEX)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
string(REGEX REPLACE "((0x[0-9a-f][0-9a-f],){32})" "\\1\n" bytes "${bytes}")
file(WRITE "${OUT}" "// Generated from ${IN} by gpu/sdf/embed_text.cmake.\nnamespace vffx::gl {\nextern const unsigned char kPnanovdbText[];\nconst unsigned char kPnanovdbText[] = {\n${bytes}0x00};\n}  // namespace vffx::gl\n")
