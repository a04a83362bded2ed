// tinyobjloader's implementation, compiled into the fuzz target with the fuzzer's
// instrumentation (the renderer itself links Debian's shared library).
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
