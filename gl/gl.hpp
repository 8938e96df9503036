// The OpenGL 4.5 core functions render/ and the GPU methods use, loaded through the context's own GetProcAddress (OSMesa or
// EGL): no GL library is linked, so no dispatcher stands between a call and the context that is current.
#pragma once

#include <GL/glcorearb.h>

#include <stdexcept>
#include <string>

namespace stepwise::gl {

#define STEPWISE_GL_FUNCTIONS(X)                                                                        \
  X(PFNGLGETSTRINGPROC, GetString)                                                                      \
  X(PFNGLGETERRORPROC, GetError)                                                                        \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                                                                  \
  X(PFNGLENABLEPROC, Enable)                                                                            \
  X(PFNGLDISABLEPROC, Disable)                                                                          \
  X(PFNGLVIEWPORTPROC, Viewport)                                                                        \
  X(PFNGLBLENDFUNCPROC, BlendFunc)                                                                      \
  X(PFNGLDEPTHMASKPROC, DepthMask)                                                                      \
  X(PFNGLCULLFACEPROC, CullFace)                                                                        \
  X(PFNGLPOLYGONOFFSETPROC, PolygonOffset)                                                              \
  X(PFNGLFINISHPROC, Finish)                                                                            \
  X(PFNGLREADPIXELSPROC, ReadPixels)                                                                    \
  X(PFNGLPIXELSTOREIPROC, PixelStorei)                                                                  \
  X(PFNGLCREATESHADERPROC, CreateShader)                                                                \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                                                                \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                                                              \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                                                                  \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                                                        \
  X(PFNGLDELETESHADERPROC, DeleteShader)                                                                \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                                                              \
  X(PFNGLATTACHSHADERPROC, AttachShader)                                                                \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                                                                  \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                                                                \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                                                      \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                                                              \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                                                                    \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                                                    \
  X(PFNGLUNIFORM1IPROC, Uniform1i)                                                                      \
  X(PFNGLUNIFORM1FPROC, Uniform1f)                                                                      \
  X(PFNGLUNIFORM1FVPROC, Uniform1fv)                                                                    \
  X(PFNGLUNIFORM1IVPROC, Uniform1iv)                                                                    \
  X(PFNGLUNIFORM2IPROC, Uniform2i)                                                                      \
  X(PFNGLUNIFORM2FPROC, Uniform2f)                                                                      \
  X(PFNGLUNIFORM3FVPROC, Uniform3fv)                                                                    \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)                                                        \
  X(PFNGLCREATEVERTEXARRAYSPROC, CreateVertexArrays)                                                    \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                                                    \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                                                          \
  X(PFNGLCREATEBUFFERSPROC, CreateBuffers)                                                              \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                                                              \
  X(PFNGLNAMEDBUFFERDATAPROC, NamedBufferData)                                                          \
  X(PFNGLVERTEXARRAYVERTEXBUFFERPROC, VertexArrayVertexBuffer)                                          \
  X(PFNGLVERTEXARRAYATTRIBFORMATPROC, VertexArrayAttribFormat)                                          \
  X(PFNGLVERTEXARRAYATTRIBBINDINGPROC, VertexArrayAttribBinding)                                        \
  X(PFNGLVERTEXARRAYBINDINGDIVISORPROC, VertexArrayBindingDivisor)                                      \
  X(PFNGLENABLEVERTEXARRAYATTRIBPROC, EnableVertexArrayAttrib)                                          \
  X(PFNGLDRAWARRAYSPROC, DrawArrays)                                                                    \
  X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)                                                  \
  X(PFNGLCREATETEXTURESPROC, CreateTextures)                                                            \
  X(PFNGLDELETETEXTURESPROC, DeleteTextures)                                                            \
  X(PFNGLTEXTURESTORAGE2DPROC, TextureStorage2D)                                                        \
  X(PFNGLTEXTUREPARAMETERIPROC, TextureParameteri)                                                      \
  X(PFNGLBINDTEXTUREUNITPROC, BindTextureUnit)                                                          \
  X(PFNGLGETTEXTUREIMAGEPROC, GetTextureImage)                                                          \
  X(PFNGLTEXTURESUBIMAGE2DPROC, TextureSubImage2D)                                                      \
  X(PFNGLCREATERENDERBUFFERSPROC, CreateRenderbuffers)                                                  \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)                                                  \
  X(PFNGLNAMEDRENDERBUFFERSTORAGEPROC, NamedRenderbufferStorage)                                        \
  X(PFNGLCREATEFRAMEBUFFERSPROC, CreateFramebuffers)                                                    \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                                                    \
  X(PFNGLNAMEDFRAMEBUFFERTEXTUREPROC, NamedFramebufferTexture)                                          \
  X(PFNGLNAMEDFRAMEBUFFERRENDERBUFFERPROC, NamedFramebufferRenderbuffer)                                \
  X(PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC, CheckNamedFramebufferStatus)                                  \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                                                          \
  X(PFNGLNAMEDFRAMEBUFFERDRAWBUFFERSPROC, NamedFramebufferDrawBuffers)                                  \
  X(PFNGLCLEARNAMEDFRAMEBUFFERFVPROC, ClearNamedFramebufferfv)                                          \
  X(PFNGLCLEARNAMEDFRAMEBUFFERFIPROC, ClearNamedFramebufferfi)                                          \
  X(PFNGLGETINTEGER64VPROC, GetInteger64v)                                                              \
  X(PFNGLNAMEDBUFFERSTORAGEPROC, NamedBufferStorage)                                                    \
  X(PFNGLNAMEDBUFFERSUBDATAPROC, NamedBufferSubData)                                                    \
  X(PFNGLGETNAMEDBUFFERSUBDATAPROC, GetNamedBufferSubData)                                              \
  X(PFNGLCOPYNAMEDBUFFERSUBDATAPROC, CopyNamedBufferSubData)                                            \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                                                            \
  X(PFNGLDISPATCHCOMPUTEPROC, DispatchCompute)                                                          \
  X(PFNGLMEMORYBARRIERPROC, MemoryBarrier)

// the functions, each named as in GL without its gl prefix (gl.DrawArrays)
struct Gl {
#define STEPWISE_GL_MEMBER(type, name) type name = nullptr;
  STEPWISE_GL_FUNCTIONS(STEPWISE_GL_MEMBER)
#undef STEPWISE_GL_MEMBER
};

// a context could not be made or a GL call failed; the message says which and, where it is a missing
// package, how to install it
struct GlError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// every function through get_proc ("glDrawArrays" -> address); GlError naming the first one missing
Gl load_gl(void* (*get_proc)(const char* name));

// GlError naming `what` and the code if glGetError reports one
void check_gl(const Gl& gl, const std::string& what);

// a compiled and linked program from GLSL 4.50 sources (geometry may be empty); GlError with the log
GLuint link_program(const Gl& gl, const char* vertex, const char* geometry, const char* fragment, const std::string& name);

// a compiled and linked compute program from a GLSL 4.50 source; GlError with the log
GLuint link_compute_program(const Gl& gl, const char* compute, const std::string& name);

// "" or why `gl`'s context has no compute shaders (OpenGL before 4.3), the version it has named
std::string compute_problem(const Gl& gl);
// the same from a version's numbers and text (GL_MAJOR_VERSION, GL_MINOR_VERSION, GL_VERSION)
std::string compute_problem(int major, int minor, const std::string& version);

// a 2D texture of width x height in `format` (one level), linearly filtered, wrapping as `wrap`
// (GL_CLAMP_TO_EDGE, GL_REPEAT) in both directions
GLuint make_texture(const Gl& gl, GLenum format, int width, int height, GLenum wrap);

}  // namespace stepwise::gl
