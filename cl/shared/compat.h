/* Lets one header declare structs for both the OpenCL C device code and the C++ host.
 * On the device the vector types are the built-in ones; on the host they are the matching
 * cl_floatN types from CL/cl_platform.h, which have the same size and alignment. */
#ifndef CLBDPT_COMPAT_H
#define CLBDPT_COMPAT_H

#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)
#define CLBDPT_DEVICE 1
typedef float4 clbdpt_float4;
typedef int clbdpt_int;
typedef uint clbdpt_uint;
#else
#include <CL/cl_platform.h>
typedef cl_float4 clbdpt_float4;
typedef cl_int clbdpt_int;
typedef cl_uint clbdpt_uint;
#endif

#endif
