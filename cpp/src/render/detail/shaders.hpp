#pragma once
// GLSL 4.50 core sources of the renderer (private).
//
// Conventions: u_view maps world coordinates to the OpenCV camera frame (X_CW); u_proj maps
// OpenCV camera coordinates straight to clip space with window y = image row v (so images read
// back top row first and the winding of triangles appears reversed: front faces are clockwise).

namespace mgn::detail {

// Full pass: colour (location 0), z-depth (1), instance id (2). The fragment shader is compiled
// in four variants, MGN_TEXTURED and MGN_SHADOWS each 0 or 1 (defined after the #version line by
// the renderer): llvmpipe runs both sides of a branch on a uniform with lane masks, so a
// texture or shadow-map lookup that is not used would still cost its sampling per fragment.
inline const char* kFullVs = R"(#version 450 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_nrm;
layout(location = 2) in vec2 a_uv;
uniform mat4 u_model;
uniform mat3 u_nmat;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform mat4 u_light_vp;
out vec3 v_pw;
out vec3 v_nw;
out vec2 v_uv;
out float v_zc;
out vec4 v_pl;
invariant gl_Position;
void main() {
  vec4 pw = u_model * vec4(a_pos, 1.0);
  vec4 pc = u_view * pw;
  v_pw = pw.xyz;
  v_nw = u_nmat * a_nrm;
  v_uv = a_uv;
  v_zc = pc.z;
  v_pl = u_light_vp * pw;
  gl_Position = u_proj * pc;
}
)";

inline const char* kFullFs = R"(#version 450 core
in vec3 v_pw;
in vec3 v_nw;
in vec2 v_uv;
in float v_zc;
in vec4 v_pl;
layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_z;
layout(location = 2) out int o_id;
uniform vec3 u_base;
uniform float u_alpha;
uniform vec3 u_spec;
uniform float u_shininess;
uniform sampler2D u_tex;
uniform vec3 u_eye;
uniform vec3 u_light_pos;
uniform vec3 u_light_rgb;
uniform vec3 u_ambient;
uniform sampler2DShadow u_shadow_map;
uniform float u_shadow_texel;
uniform int u_id;
void main() {
  vec3 V = normalize(u_eye - v_pw);
  vec3 nf = cross(dFdx(v_pw), dFdy(v_pw));
  nf = length(nf) > 0.0 ? normalize(nf) : V;
  if (dot(nf, V) < 0.0) nf = -nf;
  vec3 n = length(v_nw) > 0.0 ? normalize(v_nw) : nf;
  if (dot(n, V) < 0.0) n = -n;
  if (dot(n, nf) < 0.5) n = nf;  // smooth normal across a crease: use the facet normal
  vec3 albedo = u_base;
#if MGN_TEXTURED
  albedo *= texture(u_tex, vec2(v_uv.x, 1.0 - v_uv.y)).rgb;
#endif
  vec3 Lv = u_light_pos - v_pw;
  vec3 L = normalize(Lv);
  float ndl = max(dot(n, L), 0.0);
  float vis = 1.0;
#if MGN_SHADOWS
  if (ndl > 0.0) {
    vec3 p = v_pl.xyz / v_pl.w * 0.5 + 0.5;
    if (p.z < 1.0 && all(greaterThan(p.xy, vec2(0.0))) && all(lessThan(p.xy, vec2(1.0)))) {
      // 4 bilinear comparisons (hardware 2x2 PCF each): a 3x3-texel soft edge.
      float s = 0.0;
      for (int i = 0; i < 4; ++i) {
        vec2 o = (vec2(i & 1, i >> 1) - 0.5) * u_shadow_texel;
        s += texture(u_shadow_map, vec3(p.xy + o, p.z));
      }
      vis = 0.25 * s;
    }
  }
#endif
  vec3 H = normalize(L + V);
  float spec = ndl > 0.0 ? pow(max(dot(n, H), 0.0), u_shininess) : 0.0;
  vec3 c = albedo * u_ambient + vis * u_light_rgb * (albedo * ndl + u_spec * spec);
  // Linear colour: the sRGB framebuffer encodes it (and blends in linear space).
  o_color = vec4(clamp(c, 0.0, 1.0), u_alpha);
  o_z = v_zc;
  o_id = u_id;
}
)";

// Geometry-only pass: z-depth (location 1) and instance id (2).
inline const char* kSimpleVs = R"(#version 450 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_proj;
out float v_zc;
invariant gl_Position;
void main() {
  vec4 pw = u_model * vec4(a_pos, 1.0);
  vec4 pc = u_view * pw;
  v_zc = pc.z;
  gl_Position = u_proj * pc;
}
)";

inline const char* kSimpleFs = R"(#version 450 core
in float v_zc;
layout(location = 1) out float o_z;
layout(location = 2) out int o_id;
uniform int u_id;
void main() {
  o_z = v_zc;
  o_id = u_id;
}
)";

// Shadow map pass: depth only, from the light.
inline const char* kShadowVs = R"(#version 450 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_model;
uniform mat4 u_light_vp;
void main() { gl_Position = u_light_vp * (u_model * vec4(a_pos, 1.0)); }
)";

inline const char* kShadowFs = R"(#version 450 core
void main() {}
)";

}  // namespace mgn::detail
