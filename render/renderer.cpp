#include "renderer.hpp"

#include "caustics.hpp"
#include "water_optics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

namespace stepwise::render {
namespace {

// lit geometry: position and normal per vertex; instance: centre and radius (balls), else (0, 0, 0, 1)
constexpr const char* lit_vertex = R"(#version 450 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 instance;
uniform mat4 view_projection;
out vec3 world, world_normal;
void main() {
  world = instance.xyz + instance.w * position;
  world_normal = normal;
  gl_Position = view_projection * vec4(world, 1.0);
}
)";

// mode 0: lit (Lambert with a little Blinn-Phong), both sides, back faces in back_color; 1: unlit;
// 2: lit, checkered along axis_u and axis_v (the ground); 3: unlit, the colour the field texture's value maps
// to at (world.xy - field_origin) * field_scale + field_offset (a fluid's density or vorticity, a PDE's field)
constexpr const char* lit_fragment = R"(#version 450 core
in vec3 world, world_normal;
uniform vec3 color, back_color, light, eye, axis_u, axis_v;
uniform float tile;
uniform vec2 field_origin, field_scale, field_offset;
uniform int mode, field_signed;
uniform sampler2D field;
out vec4 frag;
void main() {
  vec3 base = gl_FrontFacing ? color : back_color;
  if (mode == 1) { frag = vec4(base, 1.0); return; }
  if (mode == 3) {
    float s = texture(field, (world.xy - field_origin) * field_scale + field_offset).r;
    if (field_signed == 1)
      base = s >= 0.0 ? mix(vec3(0.97), vec3(0.75, 0.15, 0.12), min(s, 1.0)) : mix(vec3(0.97), vec3(0.15, 0.30, 0.75), min(-s, 1.0));
    else
      base = mix(vec3(0.05, 0.07, 0.12), vec3(0.96, 0.94, 0.90), clamp(s, 0.0, 1.0));
    frag = vec4(base, 1.0);
    return;
  }
  if (mode == 2) {
    float parity = mod(floor(dot(world, axis_u) / tile) + floor(dot(world, axis_v) / tile), 2.0);
    base *= parity < 0.5 ? 1.0 : 0.86;
  }
  vec3 n = normalize(world_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 v = normalize(eye - world);
  if (dot(n, v) < 0.0) n = -n;
  float diffuse = max(dot(n, light), 0.0);
  float specular = pow(max(dot(n, normalize(light + v)), 0.0), 48.0) * 0.25;
  frag = vec4(base * (0.32 + 0.68 * diffuse) + vec3(specular), 1.0);
}
)";

// the pool: floor z = -depth lit by the photon map, walls lit by the sun; tiles of side/8
constexpr const char* pool_common = R"(
uniform sampler2D photons;
uniform vec3 light;
uniform float depth, side;
vec3 pool_color(vec3 p, vec3 n) {
  float tile = side / 8.0;
  vec2 uv = abs(n.z) > 0.5 ? p.xy : (abs(n.x) > 0.5 ? p.yz : p.xz);
  float parity = mod(floor(uv.x / tile) + floor(uv.y / tile), 2.0);
  vec3 base = parity < 0.5 ? vec3(0.80, 0.84, 0.86) : vec3(0.62, 0.72, 0.78);
  if (abs(n.z) > 0.5) return base * (0.25 + 0.75 * texture(photons, p.xy / side).r);
  return base * (0.25 + 0.45 * max(dot(n, light), 0.0));
}
)";

constexpr const char* pool_vertex = R"(#version 450 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
uniform mat4 view_projection;
out vec3 world, world_normal;
void main() {
  world = position;
  world_normal = normal;
  gl_Position = view_projection * vec4(position, 1.0);
}
)";

constexpr const char* pool_fragment_body = R"(
in vec3 world, world_normal;
out vec4 frag;
void main() { frag = vec4(pool_color(world, world_normal), 1.0); }
)";

// the surface: the view ray refracted into the pool to the first wall or floor it meets, mixed with the
// sky reflected by the Fresnel reflectance; water absorbs along the refracted path
constexpr const char* surface_fragment_body = R"(
in vec3 world, world_normal;
uniform vec3 eye;
uniform float index;
out vec4 frag;
vec3 sky(vec3 d) {
  vec3 c = mix(vec3(0.78, 0.86, 0.95), vec3(0.35, 0.55, 0.85), clamp(d.z, 0.0, 1.0));
  return c + vec3(1.0, 0.95, 0.8) * pow(max(dot(d, light), 0.0), 400.0) * 4.0;
}
void main() {
  vec3 n = normalize(world_normal);
  vec3 v = normalize(world - eye);
  if (dot(n, v) > 0.0) n = -n;
  float cos_i = -dot(n, v);
  vec3 t = refract(v, n, 1.0 / index);
  // the nearest of the floor and the four walls along t
  float s = 1e30;
  vec3 hit_normal = vec3(0.0, 0.0, 1.0);
  if (t.z < 0.0) { s = (-depth - world.z) / t.z; }
  if (t.x < 0.0 && -world.x / t.x < s) { s = -world.x / t.x; hit_normal = vec3(1.0, 0.0, 0.0); }
  if (t.x > 0.0 && (side - world.x) / t.x < s) { s = (side - world.x) / t.x; hit_normal = vec3(-1.0, 0.0, 0.0); }
  if (t.y < 0.0 && -world.y / t.y < s) { s = -world.y / t.y; hit_normal = vec3(0.0, 1.0, 0.0); }
  if (t.y > 0.0 && (side - world.y) / t.y < s) { s = (side - world.y) / t.y; hit_normal = vec3(0.0, -1.0, 0.0); }
  vec3 below = pool_color(world + s * t, hit_normal) * exp(-vec3(2.2, 0.7, 0.45) * s / side);
  float transmitted = fresnel_transmittance(cos_i, index);
  frag = vec4(mix(sky(reflect(v, n)), below, transmitted), 1.0);
}
)";

// a tube of radius r around each segment of a polyline: 8 sides, normals outward
void append_tube(std::vector<float>& out, const std::vector<Eigen::Vector3d>& line, double r) {
  constexpr int sides = 8;
  const auto push = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(p[k]));
    for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(n[k]));
  };
  for (size_t s = 0; s + 1 < line.size(); ++s) {
    const Eigen::Vector3d a = line[s], b = line[s + 1], axis = b - a;
    if (axis.norm() == 0) continue;
    const Eigen::Vector3d u = axis.unitOrthogonal(), w = axis.normalized().cross(u);
    for (int k = 0; k < sides; ++k) {
      const double t0 = 2 * std::numbers::pi * k / sides, t1 = 2 * std::numbers::pi * (k + 1) / sides;
      const Eigen::Vector3d n0 = std::cos(t0) * u + std::sin(t0) * w, n1 = std::cos(t1) * u + std::sin(t1) * w;
      push(a + r * n0, n0), push(b + r * n0, n0), push(b + r * n1, n1);
      push(a + r * n0, n0), push(b + r * n1, n1), push(a + r * n1, n1);
    }
  }
}

void append_triangle(std::vector<float>& out, const Eigen::Vector3d* p, const Eigen::Vector3d* n) {
  for (int v = 0; v < 3; ++v) {
    for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(p[v][k]));
    for (int k = 0; k < 3; ++k) out.push_back(static_cast<float>(n[v][k]));
  }
}

// a flat quadrilateral a b c d (counter-clockwise seen from its front), its normal (b - a) x (c - a)
void append_quad(std::vector<float>& out, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d) {
  const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
  const Eigen::Vector3d ns[3] = {n, n, n}, t1[3] = {a, b, c}, t2[3] = {a, c, d};
  append_triangle(out, t1, ns);
  append_triangle(out, t2, ns);
}

// a body's faces in world coordinates, flat shaded
void append_body(std::vector<float>& out, const Shapes::Body& body) {
  const TriangleMesh& mesh = *body.mesh;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    Eigen::Vector3d p[3];
    for (int v = 0; v < 3; ++v) p[v] = body.rotation * mesh.vertices.row(mesh.faces(f, v)).transpose() + body.position;
    const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
    const Eigen::Vector3d normals[3] = {n, n, n};
    append_triangle(out, p, normals);
  }
}

// a sheet smooth shaded: area-weighted vertex normals
void append_sheet(std::vector<float>& out, const TriangleMesh& sheet) {
  Eigen::Matrix<double, Eigen::Dynamic, 3> normals = Eigen::Matrix<double, Eigen::Dynamic, 3>::Zero(sheet.vertices.rows(), 3);
  for (Eigen::Index f = 0; f < sheet.faces.rows(); ++f) {
    const Eigen::Vector3d a = sheet.vertices.row(sheet.faces(f, 0)), b = sheet.vertices.row(sheet.faces(f, 1)), c = sheet.vertices.row(sheet.faces(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    for (int v = 0; v < 3; ++v) normals.row(sheet.faces(f, v)) += n.transpose();
  }
  for (Eigen::Index f = 0; f < sheet.faces.rows(); ++f) {
    Eigen::Vector3d p[3], n[3];
    for (int v = 0; v < 3; ++v) {
      p[v] = sheet.vertices.row(sheet.faces(f, v));
      n[v] = normals.row(sheet.faces(f, v)).transpose().normalized();
    }
    append_triangle(out, p, n);
  }
}

// the twelve edges of a box as polylines
std::vector<std::vector<Eigen::Vector3d>> box_edges(const Aabb& box) {
  std::vector<std::vector<Eigen::Vector3d>> edges;
  for (int axis = 0; axis < 3; ++axis)
    for (int corner = 0; corner < 4; ++corner) {
      Eigen::Vector3d a = box.lo;
      a[(axis + 1) % 3] = corner & 1 ? box.hi[(axis + 1) % 3] : box.lo[(axis + 1) % 3];
      a[(axis + 2) % 3] = corner & 2 ? box.hi[(axis + 2) % 3] : box.lo[(axis + 2) % 3];
      Eigen::Vector3d b = a;
      b[axis] = box.hi[axis];
      edges.push_back({a, b});
    }
  return edges;
}

const Eigen::Vector3f body_palette[] = {{0.85f, 0.33f, 0.18f}, {0.20f, 0.45f, 0.75f}, {0.90f, 0.65f, 0.15f},
                                        {0.30f, 0.65f, 0.35f}, {0.60f, 0.35f, 0.70f}};

}  // namespace

View make_view(std::span<const Shapes> frames, const Look& look, int width, int height) {
  View view;
  view.look = look;
  view.pool_depth = pool_depth(frames.front(), look);
  Aabb box;
  for (const auto& shapes : frames) {
    const Aabb b = bounds(shapes, view.pool_depth);
    box.extend(b.lo);
    box.extend(b.hi);
  }
  view.camera = frame_camera(box, frames.front(), look, static_cast<double>(width) / height);
  view.light = light_direction(view.camera, look);
  view.point_radius = 0.008 * (box.hi - box.lo).norm();
  return view;
}

struct Renderer::Impl {
  const gl::Context& context;
  const gl::Gl& gl;
  int width, height;
  GLuint lit = 0, pool = 0, surface = 0;
  GLuint framebuffer = 0, color = 0, depth = 0;
  GLuint vertex_array = 0, vertices = 0, instances = 0;
  std::unique_ptr<PhotonMap> photons;
  GLuint field_texture = 0;  // a Shapes::Field's values, R32F, field_size
  std::array<int, 2> field_size{};
  std::array<GLenum, 2> field_wrap{};
  // the unit sphere at subdivision levels 0..3 (20·4^level triangles): many balls are drawn coarser
  std::array<std::vector<float>, 4> sphere_vertices;

  Impl(const gl::Context& context_, int w, int h) : context(context_), gl(context_.gl()), width(w), height(h) {
    context.make_current();
    lit = gl::link_program(gl, lit_vertex, nullptr, lit_fragment, "lit");
    const std::string head = std::string("#version 450 core\n") + glsl_fresnel + pool_common;
    pool = gl::link_program(gl, pool_vertex, nullptr, (head + pool_fragment_body).c_str(), "pool");
    surface = gl::link_program(gl, pool_vertex, nullptr, (head + surface_fragment_body).c_str(), "water surface");
    gl.CreateRenderbuffers(1, &color);
    gl.NamedRenderbufferStorage(color, GL_RGBA8, width, height);
    gl.CreateRenderbuffers(1, &depth);
    gl.NamedRenderbufferStorage(depth, GL_DEPTH_COMPONENT24, width, height);
    gl.CreateFramebuffers(1, &framebuffer);
    gl.NamedFramebufferRenderbuffer(framebuffer, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
    gl.NamedFramebufferRenderbuffer(framebuffer, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    if (const GLenum status = gl.CheckNamedFramebufferStatus(framebuffer, GL_FRAMEBUFFER); status != GL_FRAMEBUFFER_COMPLETE)
      throw gl::GlError(fmt::format("glCheckNamedFramebufferStatus ({} x {} RGBA8 + depth) = 0x{:04x}", width, height, status));
    gl.CreateVertexArrays(1, &vertex_array);
    gl.CreateBuffers(1, &vertices);
    gl.CreateBuffers(1, &instances);
    gl.VertexArrayVertexBuffer(vertex_array, 0, vertices, 0, 6 * sizeof(float));
    gl.VertexArrayVertexBuffer(vertex_array, 1, instances, 0, 4 * sizeof(float));
    gl.VertexArrayBindingDivisor(vertex_array, 1, 1);
    for (GLuint a = 0; a < 3; ++a) {
      gl.EnableVertexArrayAttrib(vertex_array, a);
      gl.VertexArrayAttribFormat(vertex_array, a, a == 2 ? 4 : 3, GL_FLOAT, GL_FALSE, a == 1 ? 3 * sizeof(float) : 0);
      gl.VertexArrayAttribBinding(vertex_array, a, a == 2 ? 1 : 0);
    }
    // the unit sphere, smooth: its normals are its positions
    for (size_t level = 0; level < sphere_vertices.size(); ++level) {
      const TriangleMesh unit_sphere = sphere_mesh(1, static_cast<int>(level));
      for (Eigen::Index f = 0; f < unit_sphere.faces.rows(); ++f) {
        Eigen::Vector3d p[3];
        for (int v = 0; v < 3; ++v) p[v] = unit_sphere.vertices.row(unit_sphere.faces(f, v));
        append_triangle(sphere_vertices[level], p, p);
      }
    }
    gl::check_gl(gl, "renderer set-up");
  }

  ~Impl() {
    if (!context.try_make_current()) return;  // the objects are this context's
    gl.DeleteBuffers(1, &vertices);
    gl.DeleteBuffers(1, &instances);
    gl.DeleteVertexArrays(1, &vertex_array);
    gl.DeleteFramebuffers(1, &framebuffer);
    gl.DeleteRenderbuffers(1, &color);
    gl.DeleteRenderbuffers(1, &depth);
    for (const GLuint p : {lit, pool, surface}) gl.DeleteProgram(p);
    if (field_texture) gl.DeleteTextures(1, &field_texture);
  }

  void uniform(GLuint program, const char* name, const Eigen::Vector3f& v) const { gl.Uniform3fv(gl.GetUniformLocation(program, name), 1, v.data()); }
  void uniform(GLuint program, const char* name, float v) const { gl.Uniform1f(gl.GetUniformLocation(program, name), v); }

  // one batch of lit triangles (6 floats a vertex), `count` instances of (centre, radius)
  void draw_batch(const std::vector<float>& data, const std::vector<float>& instance_data, const Eigen::Vector3f& front,
                  const Eigen::Vector3f& back, int mode) {
    if (data.empty() || instance_data.empty()) return;
    gl.NamedBufferData(vertices, static_cast<GLsizeiptr>(data.size() * sizeof(float)), data.data(), GL_STREAM_DRAW);
    gl.NamedBufferData(instances, static_cast<GLsizeiptr>(instance_data.size() * sizeof(float)), instance_data.data(), GL_STREAM_DRAW);
    uniform(lit, "color", front);
    uniform(lit, "back_color", back);
    gl.Uniform1i(gl.GetUniformLocation(lit, "mode"), mode);
    gl.DrawArraysInstanced(GL_TRIANGLES, 0, static_cast<GLsizei>(data.size() / 6), static_cast<GLsizei>(instance_data.size() / 4));
  }

  // pass 1 the photon map, pass 2 the pool lit by it, then the surface refracting it and reflecting the sky
  void draw_water(const Shapes::Water& water, const View& view, const Eigen::Matrix4f& view_projection) {
    if (!photons || photons->resolution() != view.photon_resolution) photons = std::make_unique<PhotonMap>(context, view.photon_resolution);
    photons->build(water, view.light, view.pool_depth);
    gl.BindVertexArray(vertex_array);  // the photon pass bound its own
    gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    gl.Viewport(0, 0, width, height);
    gl.Enable(GL_DEPTH_TEST);

    const Pool tank(water, view.pool_depth);
    const double side = tank.side, depth = tank.depth, rim = tank.rim;
    // floor and walls, their normals pointing into the pool; the walls nearest the camera face away from it
    // and are culled (the deck, drawn with the solids, hides where they stand)
    std::vector<float> box;
    const Eigen::Vector3d p000(0, 0, -depth), p100(side, 0, -depth), p110(side, side, -depth), p010(0, side, -depth);
    const Eigen::Vector3d up(0, 0, depth + rim);
    append_quad(box, p000, p100, p110, p010);
    append_quad(box, p000, p000 + up, p100 + up, p100);
    append_quad(box, p100, p100 + up, p110 + up, p110);
    append_quad(box, p110, p110 + up, p010 + up, p010);
    append_quad(box, p010, p010 + up, p000 + up, p000);
    gl.Enable(GL_CULL_FACE);
    gl.CullFace(GL_BACK);
    gl.UseProgram(pool);
    set_pool_uniforms(pool, view, side);
    gl.UniformMatrix4fv(gl.GetUniformLocation(pool, "view_projection"), 1, GL_FALSE, view_projection.data());
    const std::vector<float> one{0, 0, 0, 1};
    gl.NamedBufferData(vertices, static_cast<GLsizeiptr>(box.size() * sizeof(float)), box.data(), GL_STREAM_DRAW);
    gl.NamedBufferData(instances, static_cast<GLsizeiptr>(one.size() * sizeof(float)), one.data(), GL_STREAM_DRAW);
    gl.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(box.size() / 6));
    gl.Disable(GL_CULL_FACE);

    // the surface: the mesh pass 1 refracted, smooth normals from the height field
    const std::vector<float>& mesh = photons->surface();
    gl.UseProgram(surface);
    set_pool_uniforms(surface, view, side);
    gl.UniformMatrix4fv(gl.GetUniformLocation(surface, "view_projection"), 1, GL_FALSE, view_projection.data());
    uniform(surface, "eye", view.camera.eye.cast<float>());
    uniform(surface, "index", static_cast<float>(water_index));
    gl.NamedBufferData(vertices, static_cast<GLsizeiptr>(mesh.size() * sizeof(float)), mesh.data(), GL_STREAM_DRAW);
    gl.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(mesh.size() / 6));
  }

  // the field's values scaled to its range (to [0, 1], or [-1, 1] signed) into a texture that repeats along a
  // periodic axis, drawn on its rectangle at z = 0 with the nodes at the texels' centres
  void draw_field(const Shapes::Field& field) {
    const int nx = field.nx, ny = field.ny;
    const std::array<GLenum, 2> wrap{field.periodic[0] ? GLenum{GL_REPEAT} : GLenum{GL_CLAMP_TO_EDGE}, field.periodic[1] ? GLenum{GL_REPEAT} : GLenum{GL_CLAMP_TO_EDGE}};
    if (field_size != std::array<int, 2>{nx, ny} || field_wrap != wrap) {
      if (field_texture) gl.DeleteTextures(1, &field_texture);
      field_texture = gl::make_texture(gl, GL_R32F, nx, ny, wrap[0]);
      gl.TextureParameteri(field_texture, GL_TEXTURE_WRAP_T, static_cast<GLint>(wrap[1]));
      field_size = {nx, ny};
      field_wrap = wrap;
    }
    const double largest = field.values.cwiseAbs().maxCoeff();
    std::array<double, 2> range = field.range.value_or(std::array<double, 2>{field.is_signed ? -largest : 0.0, largest});
    if (!(range[1] > range[0]) || !std::isfinite(range[1] - range[0])) range = {range[0], range[0] + 1};
    // signed: 0 stays 0, the larger end at 1; else the range onto [0, 1]
    const double low = field.is_signed ? 0 : range[0];
    const double scale = 1 / (field.is_signed ? std::max(std::abs(range[0]), std::abs(range[1])) : range[1] - range[0]);
    std::vector<float> texels(field.values.size());
    for (Eigen::Index k = 0; k < field.values.size(); ++k) texels[k] = static_cast<float>(scale * (field.values[k] - low));
    gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl.TextureSubImage2D(field_texture, 0, 0, 0, nx, ny, GL_RED, GL_FLOAT, texels.data());
    gl.BindTextureUnit(0, field_texture);
    gl.Uniform1i(gl.GetUniformLocation(lit, "field"), 0);
    gl.Uniform1i(gl.GetUniformLocation(lit, "field_signed"), field.is_signed ? 1 : 0);
    // a periodic axis's n nodes span its extent at 1/n each; another's reach its far side at node n - 1
    Eigen::Vector2f texel_scale, offset;
    for (int axis = 0; axis < 2; ++axis) {
      const int n = axis == 0 ? nx : ny;
      const double spans = field.periodic[static_cast<size_t>(axis)] ? 1.0 : (n - 1.0) / n;
      texel_scale[axis] = static_cast<float>(field.extent[axis] > 0 ? spans / field.extent[axis] : 0.0);
      offset[axis] = static_cast<float>(0.5 / n);
    }
    gl.Uniform2f(gl.GetUniformLocation(lit, "field_origin"), static_cast<float>(field.origin.x()), static_cast<float>(field.origin.y()));
    gl.Uniform2f(gl.GetUniformLocation(lit, "field_scale"), texel_scale.x(), texel_scale.y());
    gl.Uniform2f(gl.GetUniformLocation(lit, "field_offset"), offset.x(), offset.y());
    std::vector<float> rectangle;
    const Eigen::Vector3d o(field.origin.x(), field.origin.y(), 0), ex(field.extent.x(), 0, 0), ey(0, field.extent.y(), 0);
    append_quad(rectangle, o, o + ex, o + ex + ey, o + ey);
    const Eigen::Vector3f white(1, 1, 1);
    draw_batch(rectangle, {0, 0, 0, 1}, white, white, 3);
  }

  void set_pool_uniforms(GLuint program, const View& view, double side) const {
    gl.BindTextureUnit(0, photons->texture());
    gl.Uniform1i(gl.GetUniformLocation(program, "photons"), 0);
    uniform(program, "light", view.light.cast<float>());
    uniform(program, "depth", static_cast<float>(view.pool_depth));
    uniform(program, "side", static_cast<float>(side));
  }

  void render(const Shapes& shapes, const std::vector<std::vector<Eigen::Vector3d>>& trails, const View& view) {
    context.make_current();
    const Eigen::Matrix4f view_projection = view.camera.view_projection(static_cast<double>(width) / height);
    const Eigen::Vector3f bg = view.look.background;
    const float clear[4] = {bg.x(), bg.y(), bg.z(), 1};
    gl.ClearNamedFramebufferfv(framebuffer, GL_COLOR, 0, clear);
    gl.ClearNamedFramebufferfi(framebuffer, GL_DEPTH_STENCIL, 0, 1.0f, 0);
    gl.BindVertexArray(vertex_array);
    if (shapes.water) draw_water(*shapes.water, view, view_projection);

    gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    gl.Viewport(0, 0, width, height);
    gl.Enable(GL_DEPTH_TEST);
    gl.UseProgram(lit);
    gl.UniformMatrix4fv(gl.GetUniformLocation(lit, "view_projection"), 1, GL_FALSE, view_projection.data());
    uniform(lit, "light", view.light.cast<float>());
    uniform(lit, "eye", view.camera.eye.cast<float>());
    const std::vector<float> one{0, 0, 0, 1};
    const Eigen::Vector3f color = view.look.color, dark(0.25f, 0.25f, 0.28f);

    for (const auto& field : shapes.fields) draw_field(field);

    // balls, instanced on the unit sphere
    std::vector<float> balls;
    for (const auto& ball : shapes.balls)
      for (const double v : {ball.center.x(), ball.center.y(), ball.center.z(), ball.radius > 0 ? ball.radius : view.point_radius})
        balls.push_back(static_cast<float>(v));
    // the finest sphere that keeps the balls under about two million triangles (llvmpipe draws that in
    // about a second): a hundred thousand particles are icosahedra a few pixels across
    size_t level = sphere_vertices.size() - 1;
    while (level > 0 && (sphere_vertices[level].size() / 18) * shapes.balls.size() > (size_t{1} << 21)) --level;
    draw_batch(sphere_vertices[level], balls, color, color, 0);

    // bodies, one colour each from a palette
    for (size_t b = 0; b < shapes.bodies.size(); ++b) {
      std::vector<float> data;
      append_body(data, shapes.bodies[b]);
      const Eigen::Vector3f c = shapes.bodies.size() == 1 ? color : body_palette[b % std::size(body_palette)];
      draw_batch(data, one, c, c, 0);
    }
    // sheets: the front in the colour, the back in blue
    for (const auto& sheet : shapes.surfaces) {
      std::vector<float> data;
      append_sheet(data, sheet);
      draw_batch(data, one, color, Eigen::Vector3f(0.25f, 0.42f, 0.70f), 0);
    }
    // rods, the container's edges and trails as tubes
    const double rod = 0.35 * view.point_radius;
    std::vector<float> tubes;
    for (const auto& line : shapes.lines) append_tube(tubes, line, rod);
    if (shapes.container)
      for (const auto& edge : box_edges(*shapes.container)) append_tube(tubes, edge, 0.5 * rod);
    draw_batch(tubes, one, dark, dark, 0);
    std::vector<float> paths;
    for (const auto& trail : trails) append_tube(paths, trail, 0.4 * rod);
    draw_batch(paths, one, Eigen::Vector3f(0.30f, 0.50f, 0.80f), Eigen::Vector3f(0.30f, 0.50f, 0.80f), 1);

    // the ground: its line in a planar scene, else a checkered square about the scene
    if (shapes.ground) {
      const Eigen::Vector3d n = shapes.ground->normal.normalized();
      const Eigen::Vector3d target = view.camera.target;
      const Eigen::Vector3d center = target - n * (target - shapes.ground->point).dot(n);
      const double half = 2.5 * (view.camera.eye - view.camera.target).norm() * std::tan(view.camera.fov_deg * std::numbers::pi / 360);
      const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
      std::vector<float> ground;
      if (shapes.planar) {
        const Eigen::Vector3d along = Eigen::Vector3d::UnitZ().cross(n).normalized();
        append_tube(ground, {center - half * along - rod * n, center + half * along - rod * n}, rod);
        draw_batch(ground, one, dark, dark, 0);
      } else {
        const Eigen::Vector3d p[4] = {center - half * u - half * w, center + half * u - half * w, center + half * u + half * w, center - half * u + half * w};
        const Eigen::Vector3d ns[3] = {n, n, n}, a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[2], p[3]};
        append_triangle(ground, a, ns);
        append_triangle(ground, b, ns);
        uniform(lit, "axis_u", u.cast<float>());
        uniform(lit, "axis_v", w.cast<float>());
        uniform(lit, "tile", static_cast<float>(half / 10));
        gl.Enable(GL_POLYGON_OFFSET_FILL);
        gl.PolygonOffset(1, 1);
        draw_batch(ground, one, Eigen::Vector3f(0.78f, 0.78f, 0.76f), Eigen::Vector3f(0.78f, 0.78f, 0.76f), 2);
        gl.Disable(GL_POLYGON_OFFSET_FILL);
      }
    }
    // the pool's surround: a block with the pool as its hole, its top (the deck) at the rim's height
    if (shapes.water) {
      const Pool pool(*shapes.water, view.pool_depth);
      const double a = -pool.border, b = pool.side + pool.border, s = pool.side, z = pool.rim, bottom = -pool.depth;
      std::vector<float> block;
      const auto quad = [&](const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& p3) {
        append_quad(block, p0, p1, p2, p3);  // (braced corners need the parameter types)
      };
      for (const auto& [x0, y0, x1, y1] : {std::array{a, a, b, 0.0}, std::array{a, s, b, b}, std::array{a, 0.0, 0.0, s}, std::array{s, 0.0, b, s}})
        quad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z});
      uniform(lit, "axis_u", Eigen::Vector3f::UnitX());
      uniform(lit, "axis_v", Eigen::Vector3f::UnitY());
      uniform(lit, "tile", static_cast<float>(pool.side / 16));
      const Eigen::Vector3f stone(0.82f, 0.80f, 0.74f);
      draw_batch(block, one, stone, stone, 2);  // the deck paved
      block.clear();
      const Eigen::Vector3d c[4] = {{a, a, 0}, {b, a, 0}, {b, b, 0}, {a, b, 0}};
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d &p = c[k], &q = c[(k + 1) % 4];
        quad({p.x(), p.y(), bottom}, {q.x(), q.y(), bottom}, {q.x(), q.y(), z}, {p.x(), p.y(), z});
      }
      draw_batch(block, one, stone, stone, 0);  // the sides plain
    }
    gl::check_gl(gl, "drawing a frame");
  }

  // the framebuffer, top row first
  Image read() const {
    context.make_current();
    Image image{width, height, std::vector<std::uint8_t>(static_cast<size_t>(width) * height * 4)};
    std::vector<std::uint8_t> rows(image.rgba.size());
    gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl.ReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
    gl::check_gl(gl, "glReadPixels");
    const size_t stride = static_cast<size_t>(width) * 4;
    for (int r = 0; r < height; ++r)
      std::copy_n(rows.data() + static_cast<size_t>(height - 1 - r) * stride, stride, image.rgba.data() + static_cast<size_t>(r) * stride);
    return image;
  }
};

Renderer::Renderer(const gl::Context& context, int width, int height) : impl_(std::make_unique<Impl>(context, width, height)) {}
Renderer::~Renderer() = default;

void Renderer::render(const Shapes& shapes, const std::vector<std::vector<Eigen::Vector3d>>& trails, const View& view) {
  impl_->render(shapes, trails, view);
}

Image Renderer::read() const { return impl_->read(); }

Image Renderer::draw(const Shapes& shapes, const std::vector<std::vector<Eigen::Vector3d>>& trails, const View& view) {
  impl_->render(shapes, trails, view);
  return impl_->read();
}

}  // namespace stepwise::render
