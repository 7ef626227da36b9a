// The viewport's frame: the scene rendered at the viewport's size, the view shown (the colour or a
// debug view, debug_views.h) uploaded to the texture the viewport draws, and the stats line.
#include <epoxy/gl.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>

#include "editor/debug_views.h"
#include "editor/editor_app.h"

namespace kaskad::editor {

Status Editor::render_viewport(int w, int h) {
  RenderRun run;
  run.frames = 1;
  run.width = w;
  run.height = h;
  // The AOV targets cost fill rate: only for the views that show them.
  run.write_aovs = is_aov_view(view_);
  run.prewarm = prewarm_;
  const auto now = std::chrono::steady_clock::now();
  if (!opt_.script.empty())
    run.dt = 1.0 / 60.0;
  else if (last_render_.time_since_epoch().count() != 0)
    run.dt = std::min(0.1, std::chrono::duration<double>(now - last_render_).count());
  last_render_ = now;
  auto t = render_frames(player_, scene_, run);
  if (!t) return t.error();
  // Nothing drawn while the scene has meshes: the viewport says why it may be.
  const bool was_empty = empty_view_;
  empty_view_ = t->last.stats.draw_calls == 0 && !bounds_.empty();
  if (empty_view_ && !was_empty && !opt_.script.empty())
    std::printf("kaskad edit: nothing in view (the viewport says why it may be)\n");
  prewarm_ = false;
  changed_since_frame_ = false;
  if (view_ == View::colour) {
    last_frame_ = player_.renderer->read_color();
  } else if (view_ == View::probe_faces || view_ == View::sphere_map) {
    const auto& probes = t->last.probes.probes;
    const auto sel = find(selected_);
    const ProbeData::Entry* shown = probes.empty() ? nullptr : &probes.front();
    for (const auto& p : probes)
      if (sel && p.entity == *sel) shown = &p;
    if (view_ == View::probe_faces) {
      CubeMap cube;
      if (shown) cube = player_.renderer->read_probe_cube(shown->job.handle, shown->job.visible);
      last_frame_ = cube.size > 0 ? cube_strip(cube) : player_.renderer->read_color();
    } else {
      SphereMap sphere;
      if (shown) sphere = player_.renderer->read_probe_sphere(shown->job.handle);
      last_frame_ = sphere.size > 0 ? sphere_image(sphere) : player_.renderer->read_color();
    }
  } else if (view_ == View::shadow_map) {
    last_frame_ = grey(player_.renderer->read_shadow_map());
    if (last_frame_.width == 0) last_frame_ = player_.renderer->read_color();  // no shadowed light
  } else if (view_ == View::soft_maps) {
    Image maps = player_.renderer->read_soft_shadow_maps();
    // Moments and evsm's warp exceed 1: scaled so the largest value is white.
    float top = 0.0f;
    for (float v : maps.pixels) top = std::max(top, v);
    if (top > 1.0f)
      for (float& v : maps.pixels) v /= top;
    last_frame_ = maps.pixels.empty() ? player_.renderer->read_color() : grey(maps);
  } else {
    last_frame_ = aov_view(view_, player_.renderer->read_aovs());
  }
  frame_ms_.push_back(float(t->first_frame_ms));
  if (frame_ms_.size() > 120) frame_ms_.erase(frame_ms_.begin());
  {
    const auto& st = t->last.stats;
    char line[384];
    // GPU times from timer queries; on llvmpipe a pass's work can land in the next pass's timer
    // (DESIGN.md, "Facts about these machines"), so they are indications only. The parts of
    // the shadow and probe passes are shown when they ran.
    std::string parts;
    char part[64];
    for (const auto& [name, ms] : {std::pair{"lom", st.lom_gpu_ms}, std::pair{"moments", st.moments_gpu_ms},
                                   std::pair{"prefilter", st.prefilter_gpu_ms}})
      if (ms > 0.0) {
        std::snprintf(part, sizeof part, ", %s %.2f", name, ms);
        parts += part;
      }
    // Four lines whatever their contents, so that the panel below does not move from frame to
    // frame (a narrow panel cuts them; the tooltip has them whole).
    const auto& shaders = player_.renderer->shaders().stats();
    std::snprintf(line, sizeof line,
                  "%.1f ms a frame%s\n"
                  "GPU ms: shadow %.2f, probes %.2f, fwd %.2f%s\n"
                  "%d draws, %zu shadow tris, %d probe faces\n"
                  "programs: %d compiled, %d from cache",
                  t->first_frame_ms, st.visibility_reused ? ", visibility read back" : "",
                  st.shadow_gpu_ms, st.probe_gpu_ms, st.forward_gpu_ms, parts.c_str(),
                  st.draw_calls, st.shadow_triangles, st.probe_faces, shaders.programs_compiled,
                  shaders.cache_hits);
    stats_ = line;
  }
  if (!opt_.script.empty()) {
    // The stats line the editor tests read: which frames captured probe faces and drew layers.
    const auto& st = t->last.stats;
    std::printf("frame %llu: %d probe faces, %d draws, %zu shadow triangles\n",
                static_cast<unsigned long long>(scene_.frames_rendered - 1), st.probe_faces,
                st.draw_calls, st.shadow_triangles);
  }
  if (texture_w_ != last_frame_.width || texture_h_ != last_frame_.height) {
    view_texture_ = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(view_texture_.id(), 1, GL_RGBA8, last_frame_.width, last_frame_.height);
    // No mipmaps: the default minifying filter would leave the texture incomplete (black).
    glTextureParameteri(view_texture_.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(view_texture_.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    texture_w_ = last_frame_.width;
    texture_h_ = last_frame_.height;
  }
  const GLenum format = last_frame_.channels == 4 ? GL_RGBA : last_frame_.channels == 3 ? GL_RGB
                                                                                         : GL_RED;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(view_texture_.id(), 0, 0, 0, last_frame_.width, last_frame_.height, format,
                      GL_FLOAT, last_frame_.pixels.data());
  return {};
}

}  // namespace kaskad::editor
