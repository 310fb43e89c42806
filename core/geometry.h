#pragma once
/// Small geometric helpers on triangles.

#include <glm/glm.hpp>

namespace pic {

/// Barycentric weights (b0, b1, b2) of p projected onto the plane of triangle abc.
/// Weights may be negative when p lies outside; degenerate triangles give (1, 0, 0).
inline glm::vec3 barycentric(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b,
                             const glm::vec3& c) {
    glm::vec3 e1 = b - a, e2 = c - a, d = p - a;
    float d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
    float dp1 = glm::dot(d, e1), dp2 = glm::dot(d, e2);
    float det = d11 * d22 - d12 * d12;
    if (!(det > 0.0f)) return {1.0f, 0.0f, 0.0f};
    float b1 = (d22 * dp1 - d12 * dp2) / det;
    float b2 = (d11 * dp2 - d12 * dp1) / det;
    return {1.0f - b1 - b2, b1, b2};
}

/// The point of triangle abc closest to p (Ericson, Real-Time Collision Detection §5.1.5).
inline glm::vec3 closestPointOnTriangle(const glm::vec3& p, const glm::vec3& a,
                                        const glm::vec3& b, const glm::vec3& c) {
    glm::vec3 ab = b - a, ac = c - a, ap = p - a;
    float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f) return a;
    glm::vec3 bp = p - b;
    float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3) return b;
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + ab * (d1 / (d1 - d3));
    glm::vec3 cp = p - c;
    float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6) return c;
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + ac * (d2 / (d2 - d6));
    float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    float denom = 1.0f / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

/// A unit vector orthogonal to unit n, continuous except near n = −z (Duff et al. 2017).
inline void orthonormalBasis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
}

}  // namespace pic
