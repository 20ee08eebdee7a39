/* vec.h: the few vector operations the path tracer needs, on glint_vec3. */
#ifndef EX_VEC_H
#define EX_VEC_H

#include <math.h>

#include "glint.h"

typedef glint_vec3 vec3;

#define EX_PI 3.14159265358979323846f

static inline vec3 v3(float x, float y, float z)
{
    vec3 r = {x, y, z};
    return r;
}
static inline vec3 v_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v_scale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v_neg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
static inline float v_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v_cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v_len(vec3 a) { return sqrtf(v_dot(a, a)); }
static inline vec3 v_norm(vec3 a)
{
    const float l = v_len(a);
    return l > 0.0f ? v_scale(a, 1.0f / l) : a;
}
static inline vec3 v_madd(vec3 a, vec3 b, float s) /* a + b * s */
{
    return v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s);
}
static inline float v_max_comp(vec3 a) { return fmaxf(a.x, fmaxf(a.y, a.z)); }
static inline float v_max_abs(vec3 a) { return fmaxf(fabsf(a.x), fmaxf(fabsf(a.y), fabsf(a.z))); }
static inline float v_luminance(vec3 a) { return 0.2126f * a.x + 0.7152f * a.y + 0.0722f * a.z; }
static inline int v_is_zero(vec3 a) { return a.x == 0.0f && a.y == 0.0f && a.z == 0.0f; }

/* An orthonormal basis around a unit normal (Duff et al. 2017). */
typedef struct frame {
    vec3 t, b, n;
} frame;

static inline frame frame_from_normal(vec3 n)
{
    const float sign = copysignf(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    frame f;
    f.t = v3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.b = v3(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}
static inline vec3 frame_to_local(const frame *f, vec3 v)
{
    return v3(v_dot(v, f->t), v_dot(v, f->b), v_dot(v, f->n));
}
static inline vec3 frame_to_world(const frame *f, vec3 v)
{
    return v_add(v_add(v_scale(f->t, v.x), v_scale(f->b, v.y)), v_scale(f->n, v.z));
}

#endif
