#include "sim_hw/scene_variations.h"

namespace hairrig {

namespace {

template <typename Change>
void ForEachCamera(Scene* scene, Change change) {
  for (SceneCamera& camera : scene->cameras) change(camera.pipeline);
}

void Iso1600(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) { p.iso = 1600; });
}
void Jpeg70(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) {
    p.tone = CameraPipeline::Tone::kSrgb;
    p.jpeg_quality = 70;
  });
}
void Bayer(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) { p.bayer = true; });
}
// f/2 at 16 um pixels (f = 28 mm): hair 100 mm off the focus blurs by a sigma of about 1.3 px.
void Defocus(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) {
    p.f_number = 2;
    p.pixel_um = 16;
  });
}
void SoftLens(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) { p.lens_blur_px = 1.0; });
}
void WarmWhiteBalance(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) { p.white_balance = {1.3, 1.0, 0.7}; });
}
void CoolWhiteBalance(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) { p.white_balance = {0.75, 1.0, 1.35}; });
}
void UnderExposed(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) { p.exposure_ev = -1.5; });
}
void OverExposed(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) { p.exposure_ev = 1.0; });
}
void SecondPanelOff(Scene* s) {
  if (s->lights.size() > 1) s->lights.back().intensity = 0;
}
void FirstPanelDim(Scene* s) {
  if (!s->lights.empty()) s->lights.front().intensity *= 0.4;
}
void HardLight(Scene* s) { s->ambient = 0; }
void SoftLight(Scene* s) { s->ambient = 0.4; }
void WhiteMannequin(Scene* s) { s->head.albedo = {0.85, 0.85, 0.83}; }
void GreyMannequin(Scene* s) { s->head.albedo = {0.30, 0.30, 0.30}; }
void DarkSkin(Scene* s) { s->head.albedo = {0.22, 0.13, 0.08}; }
void GreyBackdrop(Scene* s) { s->backdrop_albedo = {0.30, 0.30, 0.30}; }
void WhiteBackdrop(Scene* s) { s->backdrop_albedo = {0.85, 0.85, 0.85}; }
void BlueBackdrop(Scene* s) { s->backdrop_albedo = {0.05, 0.12, 0.45}; }
void CurlsBothWays(Scene* s) { s->wig.curl_left_share = 0.5; }
void FibreSparkle(Scene* s) {
  s->hair_shading.fibre_albedo_sd = 0.25;
  s->hair_shading.fibre_grain_sd = 0.7;
  s->hair_shading.fibre_grain_mm = 0.4;
}
// Images from another renderer: a path tracer at few samples per pixel (its
// grain), fibres with strong glints of their own, a white mannequin and other
// light (more of the room's, the lower panel dimmer).
void PathTraced(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) {
    p.render_grain_sd = 0.5;
    p.tone = CameraPipeline::Tone::kSrgb;
  });
  s->hair_shading.fibre_albedo_sd = 0.35;
  s->hair_shading.fibre_grain_sd = 1.0;
  s->hair_shading.fibre_grain_mm = 0.3;
  s->ambient = 0.25;
  if (s->lights.size() > 1) s->lights.back().intensity *= 0.5;
  WhiteMannequin(s);
}
void Photograph(Scene* s) {
  ForEachCamera(s, [](CameraPipeline& p) {
    p.iso = 800;
    p.bayer = true;
    p.tone = CameraPipeline::Tone::kSrgb;
    p.jpeg_quality = 85;
    p.f_number = 4;
    p.pixel_um = 16;
    p.white_balance = {1.12, 1.0, 0.9};
  });
  FibreSparkle(s);
  GreyBackdrop(s);
  WhiteMannequin(s);
}

}  // namespace

const std::vector<SceneVariation>& SceneVariations() {
  static const std::vector<SceneVariation> variations = {
      {"iso1600", "sensor noise at ISO 1600", Iso1600},
      {"jpeg70", "sRGB tone curve and JPEG at quality 70", Jpeg70},
      {"bayer", "RGGB colour filter array, bilinear demosaicing", Bayer},
      {"defocus", "depth of field at f/2 (circle of confusion about 2.6 px 100 mm off focus)",
       Defocus},
      {"soft_lens", "a soft lens: Gaussian blur of 1 px everywhere", SoftLens},
      {"wb_warm", "white balance off towards red (R x1.3, B x0.7)", WarmWhiteBalance},
      {"wb_cool", "white balance off towards blue (R x0.75, B x1.35)", CoolWhiteBalance},
      {"under_exposed", "exposure 1.5 stops short", UnderExposed},
      {"over_exposed", "exposure 1 stop long (highlights clip)", OverExposed},
      {"second_panel_off", "the second LED panel off", SecondPanelOff},
      {"first_panel_dim", "the first LED panel at 40 %", FirstPanelDim},
      {"hard_light", "no light from the room", HardLight},
      {"soft_light", "much light from the room (ambient 0.4)", SoftLight},
      {"white_mannequin", "a white mannequin", WhiteMannequin},
      {"grey_mannequin", "a grey mannequin", GreyMannequin},
      {"dark_skin", "a dark-skinned head", DarkSkin},
      {"grey_backdrop", "a grey backdrop", GreyBackdrop},
      {"white_backdrop", "a white backdrop", WhiteBackdrop},
      {"blue_backdrop", "a blue backdrop", BlueBackdrop},
      {"fibre_sparkle", "fibres of their own shade with glints and dull stretches of 0.4 mm",
       FibreSparkle},
      {"curls_both_ways", "half the curls (wisps) wind left-handed, half right-handed",
       CurlsBothWays},
      {"path_traced",
       "another renderer's image: a path tracer's grain at few samples per pixel, strong "
       "fibre glints, room light, the lower panel at half, a white mannequin",
       PathTraced},
      {"photograph",
       "ISO 800, Bayer, sRGB JPEG 85, f/4, warm balance, sparkle, grey backdrop, white mannequin",
       Photograph},
  };
  return variations;
}

Status ApplySceneVariations(const std::vector<std::string>& names, Scene* scene) {
  for (const std::string& name : names) {
    const SceneVariation* found = nullptr;
    for (const SceneVariation& v : SceneVariations())
      if (v.name == name) found = &v;
    if (found == nullptr) {
      std::string known;
      for (const SceneVariation& v : SceneVariations())
        known += (known.empty() ? "" : ", ") + v.name;
      return InvalidArgument("unknown scene variation '" + name + "' (known: " + known + ")");
    }
    found->apply(scene);
  }
  return Status::Ok();
}

}  // namespace hairrig
