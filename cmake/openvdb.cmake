# vff_find_openvdb(): makes the imported target OpenVDB::openvdb available in the calling directory
# (libopenvdb-dev: the level-set input of vff-bake, vff-convert's .vdb export and their tests).
#
# OpenVDB ships no package config, only a find module (FindOpenVDB.cmake, installed with its own
# FindTBB, FindOpenEXR, FindBlosc ... next to it). Its pitfalls, and what this function does about them:
#   - the folder of those modules is not on CMake's default module path: it is looked up under the
#     usual library folders and prepended to CMAKE_MODULE_PATH only inside this function, so its old
#     FindOpenEXR.cmake never shadows the OpenEXR package config that vff-convert uses;
#   - TBB and Imath are found in CONFIG mode first (the Debian packages' own configs), so the
#     module's dependencies resolve to those targets (its FindTBB keeps an existing TBB::tbb);
#   - it sets BUILD_SHARED_LIBS ON: a function has its own variable scope, so nothing leaks out.
# Imported targets are visible in the directory that creates them and below, so every directory
# that links OpenVDB calls this function (the cache makes later calls cheap). Link OpenVDB into as
# few translation units as possible: its headers are heavy to compile.
function(vff_find_openvdb)
  if(TARGET OpenVDB::openvdb)
    return()
  endif()
  find_package(TBB CONFIG REQUIRED)
  find_package(Imath CONFIG REQUIRED)
  find_path(VFF_OPENVDB_MODULE_DIR FindOpenVDB.cmake
    PATH_SUFFIXES lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/OpenVDB lib/cmake/OpenVDB lib64/cmake/OpenVDB
                  share/OpenVDB/cmake
    DOC "Folder of OpenVDB's FindOpenVDB.cmake (libopenvdb-dev)")
  if(NOT VFF_OPENVDB_MODULE_DIR)
    message(FATAL_ERROR "FindOpenVDB.cmake not found: install libopenvdb-dev (scripts/setup.sh), "
                        "or set VFF_OPENVDB_MODULE_DIR to the folder that holds it")
  endif()
  list(PREPEND CMAKE_MODULE_PATH ${VFF_OPENVDB_MODULE_DIR})
  find_package(OpenVDB REQUIRED COMPONENTS openvdb)
endfunction()
