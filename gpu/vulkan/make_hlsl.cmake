# The HLSL of one vff_vk kernel, generated from its SPIR-V (cmake -P, from gpu/vulkan/CMakeLists.txt):
#   cmake -DSPIRV_CROSS=<spirv-cross> -DIN=<kernel.spv> -DOUT=<kernel.hlsl> -DPRELUDE=<prelude.hlsl>
#         -DVARIANT=<name> [-DSOURCE=<kernel.comp, its name in the header>] [-DGLSL=<what it includes>]
#         -P make_hlsl.cmake
# (SOURCE: a name in gpu/vulkan/shaders, or a path from the repository root.)
# spirv-cross writes HLSL for shader model 6.0 with the SPIR-V's names and bindings (register(bN),
# tN, uN, space0 for set 0, binding N). Two fixes make that text compile for Vulkan with glslang's
# HLSL front end, and both are checked so that a different spirv-cross fails here, not at run time:
# * the push constant block comes out as a plain cbuffer without a register, which the front end
#   would make a uniform buffer at binding 0 (the field block's); [[vk::push_constant]] keeps it a
#   push constant;
# * GLSL's umulExtended is written unchanged (no HLSL intrinsic): the prelude defines it.
if(NOT SPIRV_CROSS OR NOT IN OR NOT OUT OR NOT PRELUDE)
  message(FATAL_ERROR "make_hlsl.cmake: SPIRV_CROSS, IN, OUT and PRELUDE are required")
endif()
execute_process(COMMAND ${SPIRV_CROSS} --hlsl --shader-model 60 ${IN}
                OUTPUT_VARIABLE hlsl ERROR_VARIABLE err RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "spirv-cross --hlsl failed on ${IN}: ${err}")
endif()
set(_push "\ncbuffer VffVkPush\n")
string(FIND "${hlsl}" "${_push}" _at)
if(_at EQUAL -1)
  message(FATAL_ERROR "make_hlsl.cmake: no 'cbuffer VffVkPush' in spirv-cross's output; the push constant fix "
                      "needs updating for this spirv-cross")
endif()
string(REPLACE "${_push}" "\n[[vk::push_constant]] cbuffer VffVkPush\n" hlsl "${hlsl}")
set(_prelude "")
string(FIND "${hlsl}" "umulExtended(" _mul)
if(NOT _mul EQUAL -1)
  file(READ ${PRELUDE} _prelude)
endif()
get_filename_component(_in_name ${IN} NAME)
if(NOT SOURCE)
  set(SOURCE vff_vk_query.comp)
endif()
set(_source_path "gpu/vulkan/shaders/${SOURCE}")
if(SOURCE MATCHES "/")
  set(_source_path "${SOURCE}")
endif()
# The GLSL that the kernel includes (-DGLSL=... names it for other kernels): the scene kernel's
# vff_scene.glsl includes vff_query.glsl.
if(GLSL)
  set(_glsl "${GLSL}")
elseif(SOURCE MATCHES "refine")
  set(_glsl "gpu/glsl/vff_query.glsl and vff_refine.glsl")
elseif(SOURCE MATCHES "scene")
  set(_glsl "gpu/glsl/vff_scene.glsl and vff_query.glsl")
else()
  set(_glsl "gpu/glsl/vff_query.glsl")
endif()
file(WRITE ${OUT}.tmp
  "// Generated at build time from ${_in_name} (${_source_path} with\n"
  "// ${_glsl}, variant ${VARIANT}) by spirv-cross --hlsl --shader-model 60 and\n"
  "// gpu/vulkan/make_hlsl.cmake. Do not edit: change the GLSL. Compile for Vulkan with\n"
  "//   glslangValidator -D -V -S comp -e main\n"
  "// (gpu/README.md, \"HLSL\": bindings, what is tested, limits).\n"
  "${_prelude}${hlsl}")
# Only a changed text touches OUT, so an unchanged kernel is not recompiled.
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUT}.tmp)
