#include <CLI/CLI.hpp>
#include <map>
#include <string>

#include "cli/cli.h"
#include "rig/gltf_export.h"

namespace hairrig {

void AddExportCommand(CLI::App& app, CommonOptions& common, Dispatch& dispatch) {
  auto* cmd = app.add_subcommand(
      "export",
      "A capture's strands, head and simulation as binary glTF (.glb) for Blender and three.js, "
      "with a decimated copy for display");
  auto options = std::make_shared<GltfExportOptions>();
  cmd->add_option("DIR", options->dir, "a capture folder with reconstruction/strands/strands.ply")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", options->out_file,
                  "the .glb to write (default DIR/reconstruction/strands/hair.glb); the display "
                  "copy goes beside it as <name>.display.glb");
  cmd->add_option("--head", options->head_file,
                  "a head file (default: DIR's fitted head, else its rig.yaml's)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--simulation", options->simulation_dir,
                  "a `hairrig simulate` output folder to add as an animation")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--model", options->model_file,
                  "the fitted model (`hairrig fit`) naming each strand's wisp (default: "
                  "DIR/simulation/model.json where it exists)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--display-strands", options->display_strands, "strands in the display copy")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--display-points", options->display_points,
                  "points per strand in the display copy and the animation")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  cmd->add_option("--animation-strands", options->animation_strands,
                  "strands in each animation frame (both files)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--display-cloud", options->display_cloud,
                  "oriented points in the display copy (0: none)")
      ->check(CLI::Range(0, 10000000))
      ->capture_default_str();
  cmd->add_option("--animation-encoding", options->animation_encoding,
                  "the full file's animation: nodes (a node per frame, stepped) or morph (frame "
                  "0 and a morph target per frame, blended); the display copy's is nodes")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, GltfAnimationEncoding>{
              {"nodes", GltfAnimationEncoding::kFrameNodes},
              {"morph", GltfAnimationEncoding::kMorphTargets}},
          CLI::ignore_case))
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "simulation frames read at once (0: one per core)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--json", common.json, "print the summary as one JSON object");
  cmd->callback([options, &dispatch] {
    DispatchSummary(dispatch, [options] { return ExportCaptureGltf(*options); });
  });
}

}  // namespace hairrig
