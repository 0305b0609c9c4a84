// tinyobj_impl.cpp — tinyobjloader's implementation, compiled into the fuzz build only, with the
// sanitizers and coverage (the normal build links Debian's libtinyobjloader.so, built from this
// same header).
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
