// OSMesa / OpenGL 4.5 core implementation of mgn::Renderer (see renderer.hpp).
#define GL_GLEXT_PROTOTYPES 1
#include <GL/osmesa.h>
// osmesa.h includes GL/gl.h; the 4.5 entry points come from glext.h (exported by libOSMesa).
#include <GL/glext.h>

#include <mgn/collision/point_inside.hpp>
#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/render/renderer.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "render/detail/shaders.hpp"

namespace mgn {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kShadowSize = 1024;

using Mat4f = Eigen::Matrix4f;
using Mat3f = Eigen::Matrix3f;

GLuint compile(GLenum type, const char* src, const char* name) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetShaderInfoLog(s, sizeof(log) - 1, nullptr, log);
    glDeleteShader(s);
    throw_error<BackendError>("Renderer: shader '", name, "' failed to compile: ", log);
  }
  return s;
}

GLuint link_program(const char* vs, const char* fs, const char* name) {
  GLuint v = compile(GL_VERTEX_SHADER, vs, name);
  GLuint f = compile(GL_FRAGMENT_SHADER, fs, name);
  GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {0};
    glGetProgramInfoLog(p, sizeof(log) - 1, nullptr, log);
    glDeleteProgram(p);
    throw_error<BackendError>("Renderer: program '", name, "' failed to link: ", log);
  }
  return p;
}

/// Projection from OpenCV camera coordinates to GL clip space with window y = image row.
Mat4f cv_projection(const Intrinsics& K, double n, double f) {
  Mat4f P = Mat4f::Zero();
  const double W = K.width, H = K.height;
  P(0, 0) = static_cast<float>(2.0 * K.fx / W);
  P(0, 2) = static_cast<float>(2.0 * K.cx / W - 1.0);
  P(1, 1) = static_cast<float>(2.0 * K.fy / H);
  P(1, 2) = static_cast<float>(2.0 * K.cy / H - 1.0);
  P(2, 2) = static_cast<float>((f + n) / (f - n));
  P(2, 3) = static_cast<float>(-2.0 * f * n / (f - n));
  P(3, 2) = 1.0f;
  return P;
}

/// Standard GL perspective view-projection of a light at `eye` looking at `center`.
Mat4f light_view_projection(const Vec3d& eye, const Vec3d& center, double radius) {
  const Vec3d fwd = (center - eye).normalized();
  const Vec3d up0 = std::abs(fwd.z()) > 0.99 ? Vec3d::UnitY() : Vec3d::UnitZ();
  const Vec3d s = fwd.cross(up0).normalized();
  const Vec3d u = s.cross(fwd);
  Eigen::Matrix4d V = Eigen::Matrix4d::Identity();
  V.block<1, 3>(0, 0) = s.transpose();
  V.block<1, 3>(1, 0) = u.transpose();
  V.block<1, 3>(2, 0) = -fwd.transpose();
  V(0, 3) = -s.dot(eye);
  V(1, 3) = -u.dot(eye);
  V(2, 3) = fwd.dot(eye);
  const double dist = (center - eye).norm();
  const double half = std::asin(std::min(0.99, radius / dist)) * 1.05;
  const double n = std::max(0.01, dist - radius * 1.05), f = dist + radius * 1.05;
  const double t = 1.0 / std::tan(half);
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = t;
  P(1, 1) = t;
  P(2, 2) = -(f + n) / (f - n);
  P(2, 3) = -2.0 * f * n / (f - n);
  P(3, 2) = -1.0;
  return (P * V).cast<float>();
}

Vec3d hsv_to_rgb(double h, double s, double v) {
  const double hh = 6.0 * (h - std::floor(h));
  const int i = static_cast<int>(hh) % 6;
  const double f = hh - std::floor(hh);
  const double p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (i) {
    case 0:
      return {v, t, p};
    case 1:
      return {q, v, p};
    case 2:
      return {p, v, t};
    case 3:
      return {p, q, v};
    case 4:
      return {t, p, v};
    default:
      return {v, p, q};
  }
}

struct GpuMaterial {
  Vec3f base = Vec3f::Constant(0.7f);
  float alpha = 1.0f;
  Vec3f specular = Vec3f::Constant(0.2f);
  float shininess = 20.0f;
  GLuint texture = 0;
};

struct DrawGroup {
  GLsizei first = 0;  // first index
  GLsizei count = 0;  // number of indices
  int material = -1;  // index into GpuMesh::materials, -1 = default
  bool transparent = false;
};

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  std::vector<DrawGroup> groups;
  std::vector<GpuMaterial> materials;
  Eigen::Vector3d lo, hi;  // object-frame bounds
  bool closed = false;     // watertight: the camera-inside test applies
  /// Closed and wound outwards: its back faces are always hidden behind its front faces (the
  /// camera is never inside, see check_camera_inside; the light is outside the scene bounds),
  /// so they are culled in every opaque pass (half the triangles to set up and rasterise).
  bool cull_back = false;
  std::shared_ptr<const PointInsideTest> inside;  // camera-inside test (closed meshes only)
};

void check_pose(const Pose& X, const char* what) {
  if (!X.matrix().allFinite()) throw_error<InvalidArgument>(what, ": pose has non-finite entries");
  const Mat3d R = X.linear();
  const double err = (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff();
  if (err > 1e-5 || R.determinant() < 0.0) {
    throw_error<InvalidArgument>(what, ": pose rotation must be orthonormal and right-handed");
  }
}

GLuint upload_texture(const Material& mat, const std::string& mesh_name) {
  cv::Mat img;
  if (!mat.texture_data.empty()) {
    const cv::Mat buf(1, static_cast<int>(mat.texture_data.size()), CV_8U,
                      const_cast<std::uint8_t*>(mat.texture_data.data()));
    img = cv::imdecode(buf, cv::IMREAD_COLOR);
    if (img.empty()) {
      throw_error<IoError>("Renderer::add_mesh: embedded texture of material '", mat.name,
                           "' of mesh '", mesh_name, "' could not be decoded (",
                           mat.texture_data.size(), " bytes; expected PNG or JPEG)");
    }
  } else if (!mat.texture_path.empty()) {
    img = cv::imread(mat.texture_path, cv::IMREAD_COLOR);
    if (img.empty()) {
      throw_error<IoError>("Renderer::add_mesh: texture '", mat.texture_path, "' of material '",
                           mat.name, "' could not be read");
    }
  } else {
    return 0;
  }
  if (!img.isContinuous()) img = img.clone();
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  // Row 0 of the image (its top) is uploaded first, i.e. at t = 0: the shader samples 1 - v.
  glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8, img.cols, img.rows, 0, GL_BGR, GL_UNSIGNED_BYTE,
               img.data);
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  glBindTexture(GL_TEXTURE_2D, 0);
  return tex;
}

struct FullLocs {
  GLint model, nmat, view, proj, light_vp, base, alpha, spec, shininess, tex, eye, light_pos,
      light_rgb, ambient, shadow_map, shadow_texel, id;
};

/// The full fragment shader with MGN_TEXTURED and MGN_SHADOWS defined (0 or 1) after its
/// #version line (see detail/shaders.hpp).
std::string full_fragment_source(bool textured, bool shadows) {
  const std::string src = detail::kFullFs;
  const std::size_t eol = src.find('\n') + 1;
  return src.substr(0, eol) + "#define MGN_TEXTURED " + (textured ? "1" : "0") +
         "\n#define MGN_SHADOWS " + (shadows ? "1" : "0") + "\n" + src.substr(eol);
}
struct SimpleLocs {
  GLint model, view, proj, id;
};
struct ShadowLocs {
  GLint model, light_vp;
};

}  // namespace

Vec3d color_temperature_rgb(double kelvin) {
  if (!(std::isfinite(kelvin) && kelvin >= 1000.0 && kelvin <= 40000.0)) {
    throw_error<InvalidArgument>("color_temperature_rgb: expected 1000..40000 K, got ", kelvin);
  }
  constexpr double c2 = 1.438777e-2;  // second radiation constant h c / k_B, m K
  const double lambdas[3] = {610e-9, 550e-9, 465e-9};
  auto planck = [&](double l, double T) {
    return 1.0 / (std::pow(l, 5) * std::expm1(c2 / (l * T)));
  };
  Vec3d rgb;
  for (int i = 0; i < 3; ++i) rgb[i] = planck(lambdas[i], kelvin) / planck(lambdas[i], 6500.0);
  return rgb / rgb.maxCoeff();
}

struct Renderer::Impl {
  std::mutex mutex;
  int max_w = 0, max_h = 0;
  OSMesaContext ctx = nullptr;
  std::vector<unsigned char> dummy;  // OSMesa default framebuffer (unused: we draw to FBOs)
  GLuint fbo = 0, rb_color = 0, rb_z = 0, rb_id = 0, rb_depth = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;
  /// Full-pass programs by [textured][shadows] (shader variants, see detail/shaders.hpp).
  GLuint prog_full[2][2] = {{0, 0}, {0, 0}};
  GLuint prog_simple = 0, prog_shadow = 0;
  FullLocs lf[2][2]{};
  SimpleLocs ls{};
  ShadowLocs lsh{};
  std::vector<GpuMesh> meshes;
  std::vector<Instance> instances;

  void make_current() {
    if (!OSMesaMakeCurrent(ctx, dummy.data(), GL_UNSIGNED_BYTE, 16, 16)) {
      throw_error<BackendError>("Renderer: OSMesaMakeCurrent failed");
    }
  }
};

Renderer::Renderer(int max_width, int max_height) : impl_(std::make_unique<Impl>()) {
  if (max_width <= 0 || max_height <= 0 || max_width > 16384 || max_height > 16384) {
    throw_error<InvalidArgument>("Renderer: max size must be in 1..16384 px, got ", max_width, "x",
                                 max_height);
  }
  Impl& I = *impl_;
  I.max_w = max_width;
  I.max_h = max_height;
  const int attribs[] = {OSMESA_FORMAT,
                         OSMESA_RGBA,
                         OSMESA_DEPTH_BITS,
                         0,
                         OSMESA_STENCIL_BITS,
                         0,
                         OSMESA_ACCUM_BITS,
                         0,
                         OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION,
                         4,
                         OSMESA_CONTEXT_MINOR_VERSION,
                         5,
                         0};
  I.ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!I.ctx) {
    throw_error<BackendError>("Renderer: OSMesa could not create a GL 4.5 core context");
  }
  I.dummy.assign(16 * 16 * 4, 0);
  std::lock_guard<std::mutex> lock(I.mutex);
  try {
    I.make_current();
    for (int t = 0; t < 2; ++t) {
      for (int sh = 0; sh < 2; ++sh) {
        const std::string fs = full_fragment_source(t == 1, sh == 1);
        I.prog_full[t][sh] = link_program(detail::kFullVs, fs.c_str(), "full");
      }
    }
    I.prog_simple = link_program(detail::kSimpleVs, detail::kSimpleFs, "simple");
    I.prog_shadow = link_program(detail::kShadowVs, detail::kShadowFs, "shadow");
    auto u = [](GLuint p, const char* n) { return glGetUniformLocation(p, n); };
    GLuint p = 0;
    for (int t = 0; t < 2; ++t) {
      for (int sh = 0; sh < 2; ++sh) {
        p = I.prog_full[t][sh];
        I.lf[t][sh] = {u(p, "u_model"),        u(p, "u_nmat"),     u(p, "u_view"),
                       u(p, "u_proj"),         u(p, "u_light_vp"), u(p, "u_base"),
                       u(p, "u_alpha"),        u(p, "u_spec"),     u(p, "u_shininess"),
                       u(p, "u_tex"),          u(p, "u_eye"),      u(p, "u_light_pos"),
                       u(p, "u_light_rgb"),    u(p, "u_ambient"),  u(p, "u_shadow_map"),
                       u(p, "u_shadow_texel"), u(p, "u_id")};
      }
    }
    p = I.prog_simple;
    I.ls = {u(p, "u_model"), u(p, "u_view"), u(p, "u_proj"), u(p, "u_id")};
    p = I.prog_shadow;
    I.lsh = {u(p, "u_model"), u(p, "u_light_vp")};

    // Main framebuffer: colour, z-depth, instance id, depth buffer.
    glGenFramebuffers(1, &I.fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, I.fbo);
    auto rb = [&](GLenum fmt, GLenum attach) {
      GLuint r = 0;
      glGenRenderbuffers(1, &r);
      glBindRenderbuffer(GL_RENDERBUFFER, r);
      glRenderbufferStorage(GL_RENDERBUFFER, fmt, max_width, max_height);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, attach, GL_RENDERBUFFER, r);
      return r;
    };
    I.rb_color = rb(GL_SRGB8_ALPHA8, GL_COLOR_ATTACHMENT0);
    I.rb_z = rb(GL_R32F, GL_COLOR_ATTACHMENT1);
    I.rb_id = rb(GL_R32I, GL_COLOR_ATTACHMENT2);
    I.rb_depth = rb(GL_DEPTH_COMPONENT32F, GL_DEPTH_ATTACHMENT);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw_error<BackendError>("Renderer: main framebuffer incomplete (", max_width, "x",
                                max_height, ")");
    }
    // Shadow map.
    glGenTextures(1, &I.shadow_tex);
    glBindTexture(GL_TEXTURE_2D, I.shadow_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, kShadowSize, kShadowSize, 0,
                 GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &I.shadow_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, I.shadow_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, I.shadow_tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw_error<BackendError>("Renderer: shadow framebuffer incomplete");
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  } catch (...) {
    OSMesaDestroyContext(I.ctx);
    I.ctx = nullptr;
    throw;
  }
}

Renderer::~Renderer() {
  if (!impl_ || !impl_->ctx) return;
  Impl& I = *impl_;
  std::lock_guard<std::mutex> lock(I.mutex);
  if (OSMesaMakeCurrent(I.ctx, I.dummy.data(), GL_UNSIGNED_BYTE, 16, 16)) {
    for (GpuMesh& m : I.meshes) {
      for (GpuMaterial& mat : m.materials)
        if (mat.texture) glDeleteTextures(1, &mat.texture);
      glDeleteBuffers(1, &m.vbo);
      glDeleteBuffers(1, &m.ebo);
      glDeleteVertexArrays(1, &m.vao);
    }
    const GLuint rbs[] = {I.rb_color, I.rb_z, I.rb_id, I.rb_depth};
    glDeleteRenderbuffers(4, rbs);
    glDeleteFramebuffers(1, &I.fbo);
    glDeleteFramebuffers(1, &I.shadow_fbo);
    glDeleteTextures(1, &I.shadow_tex);
    for (auto& row : I.prog_full)
      for (GLuint prog : row) glDeleteProgram(prog);
    glDeleteProgram(I.prog_simple);
    glDeleteProgram(I.prog_shadow);
  }
  OSMesaDestroyContext(I.ctx);
}

int Renderer::max_width() const { return impl_->max_w; }
int Renderer::max_height() const { return impl_->max_h; }
int Renderer::num_meshes() const { return static_cast<int>(impl_->meshes.size()); }
const std::vector<Instance>& Renderer::instances() const { return impl_->instances; }

int Renderer::add_mesh(const Mesh& mesh) {
  if (mesh.empty()) {
    throw_error<InvalidArgument>("Renderer::add_mesh: mesh '", mesh.name(),
                                 "' is empty; expected at least one face");
  }
  Impl& I = *impl_;
  std::lock_guard<std::mutex> lock(I.mutex);
  const Points3f& V = mesh.vertices();
  const Faces& F = mesh.faces();
  const Eigen::Index nv = V.rows(), nf = F.rows();
  // Area-weighted vertex normals (vertices shared only where the mesh shares them).
  Points3f N = Points3f::Zero(nv, 3);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const Vec3f a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Vec3f n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n.transpose();
  }
  for (Eigen::Index v = 0; v < nv; ++v) {
    const float len = N.row(v).norm();
    if (len > 0.0f) N.row(v) /= len;
  }
  const bool has_uv = mesh.uvs().rows() == nv;
  std::vector<float> interleaved(static_cast<std::size_t>(nv) * 8);
  for (Eigen::Index v = 0; v < nv; ++v) {
    float* o = &interleaved[static_cast<std::size_t>(v) * 8];
    o[0] = V(v, 0), o[1] = V(v, 1), o[2] = V(v, 2);
    o[3] = N(v, 0), o[4] = N(v, 1), o[5] = N(v, 2);
    o[6] = has_uv ? mesh.uvs()(v, 0) : 0.0f;
    o[7] = has_uv ? mesh.uvs()(v, 1) : 0.0f;
  }
  GpuMesh g;
  const auto& mats = mesh.materials();
  try {
    I.make_current();
    for (const Material& m : mats) {
      GpuMaterial gm;
      gm.base = m.base_color.head<3>();
      gm.alpha = std::clamp(m.opacity * m.base_color[3], 0.0f, 1.0f);
      gm.specular = m.specular;
      gm.shininess = std::max(1.0f, m.shininess);
      if (has_uv) gm.texture = upload_texture(m, mesh.name());
      g.materials.push_back(gm);
    }
  } catch (...) {
    for (GpuMaterial& gm : g.materials)
      if (gm.texture) glDeleteTextures(1, &gm.texture);
    throw;
  }
  // Faces grouped by material (stable order), one draw call per group.
  const auto& fm = mesh.face_materials();
  std::vector<int> mat_of(static_cast<std::size_t>(nf), mats.empty() ? -1 : 0);
  if (!fm.empty())
    for (Eigen::Index f = 0; f < nf; ++f) mat_of[f] = fm[f];
  std::vector<std::int64_t> order(static_cast<std::size_t>(nf));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::int64_t a, std::int64_t b) { return mat_of[a] < mat_of[b]; });
  std::vector<std::uint32_t> indices;
  indices.reserve(static_cast<std::size_t>(nf) * 3);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::int64_t f = order[k];
    if (k == 0 || mat_of[f] != mat_of[order[k - 1]]) {
      DrawGroup dg;
      dg.first = static_cast<GLsizei>(indices.size());
      dg.material = mat_of[f];
      dg.transparent = dg.material >= 0 && g.materials[dg.material].alpha < 0.999f;
      g.groups.push_back(dg);
    }
    for (int c = 0; c < 3; ++c) indices.push_back(static_cast<std::uint32_t>(F(f, c)));
    g.groups.back().count += 3;
  }
  glGenVertexArrays(1, &g.vao);
  glBindVertexArray(g.vao);
  glGenBuffers(1, &g.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(interleaved.size() * sizeof(float)),
               interleaved.data(), GL_STATIC_DRAW);
  glGenBuffers(1, &g.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  const GLsizei stride = 8 * sizeof(float);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(0));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride,
                        reinterpret_cast<void*>(6 * sizeof(float)));
  glBindVertexArray(0);
  const auto b = mesh.bounds();
  g.lo = b.row(0).transpose();
  g.hi = b.row(1).transpose();
  const auto report = mesh.validate();
  g.closed = report.is_watertight;
  g.cull_back = report.is_watertight && report.is_outward;
  if (g.closed) g.inside = std::make_shared<const PointInsideTest>(mesh);
  I.meshes.push_back(std::move(g));
  return static_cast<int>(I.meshes.size()) - 1;
}

void Renderer::set_instances(std::vector<Instance> instances) {
  Impl& I = *impl_;
  std::lock_guard<std::mutex> lock(I.mutex);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const Instance& in = instances[i];
    if (in.mesh_id < 0 || in.mesh_id >= static_cast<int>(I.meshes.size())) {
      throw_error<InvalidArgument>("Renderer::set_instances: instance ", i, " has mesh_id ",
                                   in.mesh_id, "; expected 0..", I.meshes.size(), " - 1");
    }
    if (in.instance_id < 0) {
      throw_error<InvalidArgument>("Renderer::set_instances: instance ", i, " has instance_id ",
                                   in.instance_id, "; expected >= 0");
    }
    const std::string what = "Renderer::set_instances: instance " + std::to_string(i);
    check_pose(in.X_WO, what.c_str());
  }
  I.instances = std::move(instances);
}

namespace {

/// What one render call draws: the selected instances (indices into Renderer::Impl::instances)
/// and the camera-dependent bounds of their geometry.
struct Frame {
  std::vector<std::size_t> drawn;
  Vec3d eye = Vec3d::Zero();  // camera centre, world frame, m
  Pose X_CW = Pose::Identity();
  double znear = 0.0, zfar = 0.0;  // clip planes, m
  Vec3d center = Vec3d::Zero();    // centre of the world bounds of the drawn geometry, m
  double radius = 0.0;             // half diagonal of those bounds, m
};

/// Back-face culling of closed outward meshes (GpuMesh::cull_back); `front` is the winding of
/// front faces in window space.
void set_culling(bool cull, GLenum front) {
  if (cull) {
    glEnable(GL_CULL_FACE);
    glFrontFace(front);
    glCullFace(GL_BACK);
  } else {
    glDisable(GL_CULL_FACE);
  }
}

/// The steps of Renderer::render, in the order it calls them (all under the renderer's mutex).
struct RenderSteps {
  Renderer::Impl& I;
  const CameraView& view;
  const RenderOptions& opt;
  Frame frame{};
  LightSample light{};
  std::vector<Vec3f> random_colors{};  // per instance, used when opt.randomize
  bool full = false;                   // colour requested: the shading program runs
  bool shadows = false;                // shadow map in use
  Mat4f light_vp = Mat4f::Identity();

  /// Checks the view size and the requested passes.
  void validate() const {
    view.validate("Renderer::render: view");
    const Intrinsics& K = view.K;
    if (K.width > I.max_w || K.height > I.max_h) {
      throw_error<InvalidArgument>("Renderer::render: view is ", K.width, "x", K.height,
                                   " px but the renderer was created for at most ", I.max_w, "x",
                                   I.max_h);
    }
    opt.validate();
  }

  /// The instances to draw (all, or those in opt.visible_instances).
  void select_instances() {
    for (std::size_t i = 0; i < I.instances.size(); ++i) {
      if (opt.visible_instances.empty() ||
          std::find(opt.visible_instances.begin(), opt.visible_instances.end(),
                    I.instances[i].instance_id) != opt.visible_instances.end()) {
        frame.drawn.push_back(i);
      }
    }
    if (frame.drawn.empty()) {
      throw_error<InvalidArgument>(
          "Renderer::render: nothing to draw (", I.instances.size(), " instances, ",
          opt.visible_instances.size(),
          " visible_instances requested); expected a non-empty scene (set_instances)");
    }
  }

  /// World bounds of what is drawn, clip planes, and the camera-inside test.
  void bound_scene() {
    frame.eye = view.X_WC.translation();
    Vec3d wlo = Vec3d::Constant(1e300), whi = Vec3d::Constant(-1e300);
    frame.X_CW = view.X_WC.inverse();
    double zmin = 1e300, zmax = -1e300;
    for (std::size_t i : frame.drawn) {
      const Instance& in = I.instances[i];
      const GpuMesh& m = I.meshes[in.mesh_id];
      for (int c = 0; c < 8; ++c) {
        const Vec3d p_O((c & 1) ? m.hi.x() : m.lo.x(), (c & 2) ? m.hi.y() : m.lo.y(),
                        (c & 4) ? m.hi.z() : m.lo.z());
        const Vec3d p_W = in.X_WO * p_O;
        wlo = wlo.cwiseMin(p_W);
        whi = whi.cwiseMax(p_W);
        const double z = (frame.X_CW * p_W).z();
        zmin = std::min(zmin, z);
        zmax = std::max(zmax, z);
      }
      if (opt.check_camera_inside && m.closed &&
          m.inside->contains(in.X_WO.inverse() * frame.eye)) {
        const Vec3d& eye = frame.eye;
        throw_error<InvalidArgument>("Renderer::render: the camera centre (", eye.x(), ", ",
                                     eye.y(), ", ", eye.z(), ") m is inside instance ",
                                     in.instance_id, " (mesh ", in.mesh_id,
                                     "); expected a camera outside every solid");
      }
    }
    if (zmax <= 0.0) {
      throw_error<InvalidArgument>(
          "Renderer::render: the whole scene is behind the camera "
          "(camera-frame z of its bounds <= 0); check X_WC");
    }
    frame.znear = std::max(zmin * 0.99, std::max(1e-3, zmax * 1e-5));
    frame.zfar = std::max(zmax * 1.01 + 1e-3, frame.znear * 2.0);
    frame.center = 0.5 * (wlo + whi);
    frame.radius = std::max(0.5 * (whi - wlo).norm(), 1e-3);
  }

  /// The light (opt.light, or a random one with random instance colours when opt.randomize).
  void choose_light() {
    light = opt.light;
    random_colors.assign(I.instances.size(), Vec3f::Zero());
    if (opt.randomize) {
      Rng rng(opt.seed, opt.view_index);
      const double r = rng.uniform(1.0, 2.0), tilt = rng.uniform(0.0, 0.7),
                   az = rng.uniform(0.0, 2.0 * kPi);
      light.position_W = frame.center + r * Vec3d(std::cos(az) * std::sin(tilt),
                                                  std::sin(az) * std::sin(tilt), std::cos(tilt));
      light.intensity = rng.uniform(0.6, 1.3);
      light.color_temperature = rng.uniform(3000.0, 8000.0);
      light.ambient = rng.uniform(0.1, 0.35);
      for (std::size_t i = 0; i < I.instances.size(); ++i) {
        if (!I.instances[i].randomize_color) continue;
        const double h = rng.uniform(), s = rng.uniform(0.1, 0.9), v = rng.uniform(0.15, 0.9);
        random_colors[i] = hsv_to_rgb(h, s, v).cast<float>();
      }
    } else {
      if (!light.position_W.allFinite()) light.position_W = frame.center + Vec3d(0.3, -0.2, 1.5);
    }
    full = opt.rgb;
    const double light_dist = (light.position_W - frame.center).norm();
    shadows = full && opt.shadows && light_dist > frame.radius * 1.1;
  }

  /// Shadow map of the opaque groups seen from the light (only when `shadows`); sets light_vp.
  void shadow_pass() {
    if (!shadows) return;
    light_vp = light_view_projection(light.position_W, frame.center, frame.radius);
    glBindFramebuffer(GL_FRAMEBUFFER, I.shadow_fbo);
    glViewport(0, 0, kShadowSize, kShadowSize);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(2.0f, 4.0f);
    glUseProgram(I.prog_shadow);
    glUniformMatrix4fv(I.lsh.light_vp, 1, GL_FALSE, light_vp.data());
    for (std::size_t i : frame.drawn) {
      const Instance& in = I.instances[i];
      const GpuMesh& m = I.meshes[in.mesh_id];
      const Mat4f model = in.X_WO.matrix().cast<float>();
      glUniformMatrix4fv(I.lsh.model, 1, GL_FALSE, model.data());
      set_culling(m.cull_back, GL_CCW);  // a standard GL projection: front faces anticlockwise
      glBindVertexArray(m.vao);
      for (const DrawGroup& dg : m.groups) {
        if (dg.material >= 0 && m.materials[dg.material].alpha < 0.5f) continue;
        glDrawElements(GL_TRIANGLES, dg.count, GL_UNSIGNED_INT,
                       reinterpret_cast<void*>(static_cast<std::size_t>(dg.first) * 4));
      }
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    glDisable(GL_CULL_FACE);
  }

  /// Binds the main framebuffer and clears colour (background), z-depth, ids and depth.
  void clear_targets() {
    glBindFramebuffer(GL_FRAMEBUFFER, I.fbo);
    glViewport(0, 0, view.K.width, view.K.height);
    const GLenum all_bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, all_bufs);
    glEnable(GL_FRAMEBUFFER_SRGB);  // linear shader output and clear colour, sRGB storage
    const GLfloat bg[4] = {std::clamp(opt.background.x(), 0.0f, 1.0f),
                           std::clamp(opt.background.y(), 0.0f, 1.0f),
                           std::clamp(opt.background.z(), 0.0f, 1.0f), 1.0f};
    const GLfloat zero_f[4] = {0, 0, 0, 0};
    const GLint zero_i[4] = {0, 0, 0, 0};
    const GLfloat one = 1.0f;
    glClearBufferfv(GL_COLOR, 0, bg);
    glClearBufferfv(GL_COLOR, 1, zero_f);
    glClearBufferiv(GL_COLOR, 2, zero_i);
    glClearBufferfv(GL_DEPTH, 0, &one);
  }

  /// Per-frame uniforms of both programs: camera, and light and shadow map for shading.
  void set_frame_uniforms() {
    const Mat4f view_m = frame.X_CW.matrix().cast<float>();
    const Mat4f proj = cv_projection(view.K, frame.znear, frame.zfar);
    glUseProgram(I.prog_simple);
    glUniformMatrix4fv(I.ls.view, 1, GL_FALSE, view_m.data());
    glUniformMatrix4fv(I.ls.proj, 1, GL_FALSE, proj.data());
    if (!full) return;
    const Vec3f eyef = frame.eye.cast<float>(), lp = light.position_W.cast<float>();
    const Vec3f lrgb =
        (color_temperature_rgb(light.color_temperature) * light.intensity).cast<float>();
    const Vec3f amb = Vec3f::Constant(static_cast<float>(light.ambient));
    for (int t = 0; t < 2; ++t) {
      const FullLocs& lf = I.lf[t][shadows ? 1 : 0];
      glUseProgram(I.prog_full[t][shadows ? 1 : 0]);
      glUniformMatrix4fv(lf.view, 1, GL_FALSE, view_m.data());
      glUniformMatrix4fv(lf.proj, 1, GL_FALSE, proj.data());
      glUniformMatrix4fv(lf.light_vp, 1, GL_FALSE, light_vp.data());
      glUniform3fv(lf.eye, 1, eyef.data());
      glUniform3fv(lf.light_pos, 1, lp.data());
      glUniform3fv(lf.light_rgb, 1, lrgb.data());
      glUniform3fv(lf.ambient, 1, amb.data());
      glUniform1f(lf.shadow_texel, 1.0f / kShadowSize);
      glUniform1i(lf.tex, 0);
      glUniform1i(lf.shadow_map, 1);
    }
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, I.shadow_tex);
    glActiveTexture(GL_TEXTURE0);
  }

  /// Binds the instance's mesh; for the geometry pass (!shade) also sets the per-instance
  /// uniforms of the simple program (the shading programs get theirs in draw_group).
  void bind_instance(std::size_t i, bool shade) const {
    const Instance& in = I.instances[i];
    if (!shade) {
      const Mat4f model = in.X_WO.matrix().cast<float>();
      glUniformMatrix4fv(I.ls.model, 1, GL_FALSE, model.data());
      glUniform1i(I.ls.id, in.instance_id);
    }
    glBindVertexArray(I.meshes[in.mesh_id].vao);
  }

  /// Draws one group of instance i (when shading: with its material, by the program variant
  /// of its texture and of the frame's shadows).
  void draw_group(std::size_t i, const DrawGroup& dg, bool shade) const {
    const Instance& in = I.instances[i];
    const GpuMesh& m = I.meshes[in.mesh_id];
    if (shade) {
      GpuMaterial mat = dg.material >= 0 ? m.materials[dg.material] : GpuMaterial{};
      if (opt.randomize && in.randomize_color) {
        mat.base = random_colors[i];
        mat.texture = 0;
      }
      const int t = mat.texture ? 1 : 0, sh = shadows ? 1 : 0;
      const FullLocs& lf = I.lf[t][sh];
      glUseProgram(I.prog_full[t][sh]);
      const Mat4f model = in.X_WO.matrix().cast<float>();
      const Mat3f nmat = in.X_WO.linear().cast<float>();  // rigid: normal matrix = rotation
      glUniformMatrix4fv(lf.model, 1, GL_FALSE, model.data());
      glUniformMatrix3fv(lf.nmat, 1, GL_FALSE, nmat.data());
      glUniform1i(lf.id, in.instance_id);
      glUniform3fv(lf.base, 1, mat.base.data());
      glUniform1f(lf.alpha, mat.alpha);
      glUniform3fv(lf.spec, 1, mat.specular.data());
      glUniform1f(lf.shininess, mat.shininess);
      glBindTexture(GL_TEXTURE_2D, mat.texture);
    }
    glDrawElements(GL_TRIANGLES, dg.count, GL_UNSIGNED_INT,
                   reinterpret_cast<void*>(static_cast<std::size_t>(dg.first) * 4));
  }

  /// Draws the opaque groups (every group if !full) of the drawn instances with one program.
  void draw_opaque(bool shade) const {
    for (std::size_t i : frame.drawn) {
      const GpuMesh& m = I.meshes[I.instances[i].mesh_id];
      // Window y = image row flips the apparent winding: front faces are clockwise.
      set_culling(m.cull_back, GL_CW);
      bool bound = false;
      for (const DrawGroup& dg : m.groups) {
        if (full && dg.transparent) continue;
        if (!bound) bind_instance(i, shade), bound = true;
        draw_group(i, dg, shade);
      }
    }
  }

  /// Geometry pass of the opaque surfaces: z-depth, ids and the depth buffer.
  void id_depth_pass() const {
    const GLenum geo_bufs[] = {GL_NONE, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, geo_bufs);
    glUseProgram(I.prog_simple);
    draw_opaque(false);
  }

  /// Shading of the visible opaque fragments only (after id_depth_pass: no overdraw shading).
  void colour_pass() const {
    const GLenum color_bufs[] = {GL_COLOR_ATTACHMENT0, GL_NONE, GL_NONE};
    glDrawBuffers(3, color_bufs);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    draw_opaque(true);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
  }

  /// Transparent groups back to front, blended into the colour; their front faces also write
  /// z-depth and ids (depth sensors decide later what they see).
  void transparent_pass() const {
    std::vector<std::pair<double, std::size_t>> transparent;
    for (std::size_t i : frame.drawn) {
      const GpuMesh& m = I.meshes[I.instances[i].mesh_id];
      if (std::none_of(m.groups.begin(), m.groups.end(),
                       [](const DrawGroup& g) { return g.transparent; }))
        continue;
      const Vec3d c_W = I.instances[i].X_WO * (0.5 * (m.lo + m.hi));
      transparent.emplace_back((frame.X_CW * c_W).z(), i);
    }
    if (transparent.empty()) return;
    std::sort(transparent.begin(), transparent.end(),
              [](const auto& a, const auto& b) { return a.first > b.first; });
    const GLenum all_bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, all_bufs);
    glEnablei(GL_BLEND, 0);
    glDisablei(GL_BLEND, 1);
    glDisablei(GL_BLEND, 2);
    glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE);
    glEnable(GL_CULL_FACE);
    glFrontFace(GL_CW);  // window y = image row flips the apparent winding
    glCullFace(GL_BACK);
    for (const auto& t : transparent) {
      bind_instance(t.second, true);
      const GpuMesh& m = I.meshes[I.instances[t.second].mesh_id];
      for (const DrawGroup& dg : m.groups)
        if (dg.transparent) draw_group(t.second, dg, true);
    }
    glDisable(GL_CULL_FACE);
    glDisablei(GL_BLEND, 0);
  }

  /// Reads the requested images back (window y = image row: already top row first).
  RenderOutput read_back() const {
    RenderOutput out;
    out.width = view.K.width;
    out.height = view.K.height;
    out.light = light;
    const int w = view.K.width, h = view.K.height;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    const std::size_t npx = static_cast<std::size_t>(w) * h;
    if (opt.rgb) {
      out.rgb.resize(npx * 3);
      glReadBuffer(GL_COLOR_ATTACHMENT0);
      glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, out.rgb.data());
    }
    if (opt.depth) {
      out.depth.resize(npx);
      glReadBuffer(GL_COLOR_ATTACHMENT1);
      glReadPixels(0, 0, w, h, GL_RED, GL_FLOAT, out.depth.data());
    }
    if (opt.instances) {
      out.instance_ids.resize(npx);
      glReadBuffer(GL_COLOR_ATTACHMENT2);
      glReadPixels(0, 0, w, h, GL_RED_INTEGER, GL_INT, out.instance_ids.data());
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    const GLenum err = glGetError();
    if (err != GL_NO_ERROR) {
      throw_error<BackendError>("Renderer::render: OpenGL error 0x", std::hex, err);
    }
    return out;
  }
};

}  // namespace

void RenderOptions::validate() const {
  if (!rgb && !depth && !instances) {
    throw_error<InvalidArgument>(
        "RenderOptions.rgb/depth/instances must request at least one pass, got all false");
  }
  if (!background.allFinite()) {
    throw_error<InvalidArgument>("RenderOptions.background must be finite, got (",
                                 background.transpose(), ")");
  }
  if (randomize) return;  // the light is drawn, the given one is not used
  if (!(std::isfinite(light.intensity) && light.intensity >= 0.0)) {
    throw_error<InvalidArgument>("RenderOptions.light.intensity must be finite and >= 0, got ",
                                 light.intensity);
  }
  if (!(std::isfinite(light.ambient) && light.ambient >= 0.0)) {
    throw_error<InvalidArgument>("RenderOptions.light.ambient must be finite and >= 0, got ",
                                 light.ambient);
  }
}

RenderOutput Renderer::render(const CameraView& view, const RenderOptions& opt) {
  Impl& I = *impl_;
  std::lock_guard<std::mutex> lock(I.mutex);
  RenderSteps s{I, view, opt};
  s.validate();
  s.select_instances();
  s.bound_scene();
  s.choose_light();

  I.make_current();
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  s.shadow_pass();
  s.clear_targets();
  s.set_frame_uniforms();
  s.id_depth_pass();
  if (s.full) {
    s.colour_pass();
    s.transparent_pass();
  }
  glBindVertexArray(0);
  return s.read_back();
}

}  // namespace mgn
