#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/file_util.h"
#include "rig/cli.h"
#include "rig/rig_config.h"
#include "sim_hw/ground_truth.h"
#include "sim_hw/view_set.h"

namespace hairrig {
namespace {

struct RenderArgs {
  std::string scene;
  std::string out;
  int view = -1;
  bool all = false;
  bool no_noise = false;
  int threads = 2;
};

Result<std::unique_ptr<Renderer>> LoadRenderer(const std::string& scene_arg) {
  std::string path = scene_arg;
  if (path.empty()) {
    HR_ASSIGN_OR_RETURN(path, EtcPath("scenes/default.yaml"));
  }
  HR_ASSIGN_OR_RETURN(Scene scene, LoadScene(path));
  return Renderer::Create(scene);
}

Result<nlohmann::json> RenderOne(const RenderArgs& a) {
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, LoadRenderer(a.scene));
  const Scene& scene = renderer->scene();
  const int n = NumViews(scene);
  if (a.view < 0 || a.view >= n) {
    return InvalidArgument("--view " + std::to_string(a.view) + " is outside the plan's views 0-" + std::to_string(n - 1));
  }
  const std::string ext = FileExtension(a.out);
  if (ext != "png" && ext != "tif" && ext != "tiff" && ext != "jpg") {
    return InvalidArgument("--out " + a.out + ": give an image file name ending in .png, .tif or .jpg");
  }
  ViewGroundTruth g = MakeViewGroundTruth(scene, a.view);
  RenderOptions o;
  o.noise = !a.no_noise;
  o.noise_seed = scene.seed * 1000003ull + static_cast<uint64_t>(a.view);
  HR_ASSIGN_OR_RETURN(RenderedView view, renderer->Render(g.camera_index, g.turntable_deg, o));
  std::vector<uint8_t> bytes;
  if (!cv::imencode("." + ext, view.image, bytes)) return IoError(a.out + ": encoding failed");
  HR_RETURN_IF_ERROR(WriteFileAtomic(a.out, bytes.data(), bytes.size()));
  g.tags = view.tags;
  int visible = 0;
  for (const TagTruth& t : view.tags) visible += t.unoccluded ? 1 : 0;
  return nlohmann::json{{"view", a.view},          {"camera_serial", g.camera_serial}, {"turntable_deg", g.turntable_deg},
                        {"out", a.out},            {"width_px", view.image.cols},      {"height_px", view.image.rows},
                        {"tags_unoccluded", visible}};
}

Result<nlohmann::json> RenderAll(const RenderArgs& a) {
  HR_ASSIGN_OR_RETURN(std::unique_ptr<Renderer> renderer, LoadRenderer(a.scene));
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) return IoError(a.out + ": cannot create the output folder (" + ec.message() + ")");
  RenderViewsOptions o;
  o.threads = a.threads;
  o.noise = !a.no_noise;
  HR_ASSIGN_OR_RETURN(RenderViewsSummary s, RenderAllViews(*renderer, a.out, o));
  return nlohmann::json{{"views", s.views},
                        {"out", a.out},
                        {"contact_sheet", a.out + "/" + s.contact_sheet},
                        {"ground_truth", a.out + "/" + s.ground_truth},
                        {"strands", renderer->strands_turntable_mm().num_strands()},
                        {"wall_s", s.wall_s},
                        {"seconds_per_view", s.wall_s / std::max(1, s.views)}};
}

}  // namespace

void AddSimCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* sim = app.add_subcommand("sim", "The simulated rig");
  sim->require_subcommand(1);
  auto* render = sim->add_subcommand("render", "Render one view (--view N --out FILE) or all (--all --out DIR)");
  auto args = std::make_shared<RenderArgs>();
  render->add_option("--scene", args->scene, "scene file (default: etc/scenes/default.yaml)");
  auto* view = render->add_option("--view", args->view, "view index: stop * cameras + camera");
  auto* all = render->add_flag("--all", args->all, "every view, a contact sheet and the ground truth");
  view->excludes(all);
  render->add_option("--out", args->out, "output image (--view) or folder (--all)")->required();
  render->add_flag("--no-noise", args->no_noise, "render without sensor noise");
  render->add_option("--threads", args->threads, "render threads for --all")->check(CLI::Range(1, 64));
  render->add_flag("--json", common.json, "print the summary as one JSON object");
  render->callback([args, &dispatch] {
    if (!args->all && args->view < 0) throw CLI::ValidationError("sim render", "give --view N or --all");
    dispatch.action = [args]() { return args->all ? RenderAll(*args) : RenderOne(*args); };
    dispatch.print_human = [args](const nlohmann::json& j) {
      if (args->all) {
        std::printf("rendered %d views in %.1f s (%.2f s per view) to %s\ncontact sheet: %s\nground truth: %s\n",
                    j["views"].get<int>(), j["wall_s"].get<double>(), j["seconds_per_view"].get<double>(),
                    j["out"].get<std::string>().c_str(), j["contact_sheet"].get<std::string>().c_str(),
                    j["ground_truth"].get<std::string>().c_str());
      } else {
        std::printf("view %d (%s, turntable %.2f deg) -> %s\n", j["view"].get<int>(),
                    j["camera_serial"].get<std::string>().c_str(), j["turntable_deg"].get<double>(),
                    j["out"].get<std::string>().c_str());
      }
    };
  });
}

}  // namespace hairrig
