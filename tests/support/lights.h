#pragma once
/// Lights that tests build by hand.

#include <glm/glm.hpp>

#include "core/light_set.h"

namespace pic::test {

/// A point light "lamp" at `position` of `intensity` W/sr in each channel of `color`.
inline Light pointLight(glm::vec3 position, float intensity, glm::vec3 color) {
    Light light;
    light.id = "lamp";
    light.type = LightType::Point;
    light.position = position;
    light.intensity = intensity;
    light.color = color;
    return light;
}

}  // namespace pic::test
