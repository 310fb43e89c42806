#ifndef PIC_SHADERS_SHARED_GLUE_H
#define PIC_SHADERS_SHARED_GLUE_H
// Lets the headers in shaders/shared compile as both GLSL and C++ (STYLE.md 9):
// in C++ the GLSL types map to GLM and `PIC_STRUCT_CHECK` checks std430 layouts.
#ifdef __cplusplus
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
namespace pic::gpu {
using uint = uint32_t;
using vec2 = glm::vec2;
using vec3 = glm::vec3;
using vec4 = glm::vec4;
using uvec2 = glm::uvec2;
using uvec3 = glm::uvec3;
using uvec4 = glm::uvec4;
using mat4 = glm::mat4;
}  // namespace pic::gpu
#define PIC_NAMESPACE_BEGIN namespace pic::gpu {
#define PIC_NAMESPACE_END }
#define PIC_CONST(type, name, value) inline constexpr type name = value
#define PIC_STRUCT_CHECK(type, size) static_assert(sizeof(type) == (size), #type " size")
#define PIC_OFFSET_CHECK(type, field, offset) \
    static_assert(offsetof(type, field) == (offset), #type "." #field " offset")
#else
#define PIC_NAMESPACE_BEGIN
#define PIC_NAMESPACE_END
#define PIC_CONST(type, name, value) const type name = value
#define PIC_STRUCT_CHECK(type, size)
#define PIC_OFFSET_CHECK(type, field, offset)
#endif
#endif
