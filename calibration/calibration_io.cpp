#include "calibration/calibration_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/core/persistence.hpp>
#include <sstream>

#include "core/file_util.h"
#include "core/geometry_json.h"
#include "core/json_file.h"

namespace hairrig {

namespace fs = std::filesystem;

Rigid3d ObjectFromBox(const CaptureCalibration& result) {
  return result.mode == CalibrationMode::kTurntable ? result.turntable_from_box : Rigid3d();
}

namespace {

nlohmann::json StddevJson(const std::array<double, CameraIntrinsics::kNumParams>& stddev) {
  nlohmann::json sd;
  for (size_t k = 0; k < stddev.size(); ++k) sd[CameraIntrinsics::kParamNames[k]] = stddev[k];
  return sd;
}

// NaN (a rank-deficient covariance) is written as null.
nlohmann::json UncertaintyJson(const ViewUncertainty& u) {
  const auto finite = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
  };
  const auto matrix = [&](const Eigen::Matrix3d& m) {
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < 3; ++r) rows.push_back({finite(m(r, 0)), finite(m(r, 1)), finite(m(r, 2))});
    return rows;
  };
  return {{"rotation_sd_deg", finite(u.rotation_sd_deg)},
          {"centre_sd_mm", finite(u.centre_sd_mm)},
          {"projection_sd_px", finite(u.projection_sd_px)},
          {"rotation_cov_rad2", matrix(u.rotation_cov_rad2)},
          {"centre_cov_mm2", matrix(u.centre_cov_mm2)}};
}

ViewUncertainty UncertaintyFromJson(const nlohmann::json& j) {
  ViewUncertainty u;
  if (!j.is_object()) return u;
  const auto number = [](const nlohmann::json& v) { return v.is_number() ? v.get<double>() : NAN; };
  const auto matrix = [&](const nlohmann::json& rows, Eigen::Matrix3d* m) {
    if (!rows.is_array() || rows.size() != 3) return;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        (*m)(r, c) =
            rows[static_cast<size_t>(r)].is_array() && rows[static_cast<size_t>(r)].size() == 3
                ? number(rows[static_cast<size_t>(r)][static_cast<size_t>(c)])
                : NAN;
  };
  u.rotation_sd_deg = number(j.value("rotation_sd_deg", nlohmann::json()));
  u.centre_sd_mm = number(j.value("centre_sd_mm", nlohmann::json()));
  u.projection_sd_px = number(j.value("projection_sd_px", nlohmann::json()));
  matrix(j.value("rotation_cov_rad2", nlohmann::json()), &u.rotation_cov_rad2);
  matrix(j.value("centre_cov_mm2", nlohmann::json()), &u.centre_cov_mm2);
  return u;
}

constexpr int64_t kMaxIndex = std::numeric_limits<int>::max();

// Optional; each standard deviation finite and >= 0.
std::array<double, CameraIntrinsics::kNumParams> StddevField(const JsonObject& j, const char* key) {
  std::array<double, CameraIntrinsics::kNumParams> sd{};
  if (!j.Has(key)) return sd;
  const JsonObject o = j.Object(key);
  for (size_t k = 0; k < sd.size(); ++k)
    sd[k] = o.NumberOr(CameraIntrinsics::kParamNames[k], 0.0, {.min = 0});
  return sd;
}

StoredCalibration::Camera CameraFromJson(const JsonObject& j) {
  StoredCalibration::Camera camera;
  camera.name = j.StringOr("name", "");
  camera.serial = j.StringOr("serial", "");
  camera.solved = j.BoolOr("solved", false);
  if (!camera.solved) return camera;
  camera.intrinsics = IntrinsicsField(j, "intrinsics");
  camera.initial = IntrinsicsField(j, "intrinsics_initial");
  camera.intrinsics_source = j.StringOr("intrinsics_source", "");
  camera.intrinsics_stddev = StddevField(j, "intrinsics_stddev");
  return camera;
}

StoredCalibration::Tag TagFromJson(const JsonObject& j) {
  StoredCalibration::Tag t;
  t.id = static_cast<int>(j.Integer("id", {.min = 0, .max = kMaxIndex}));
  const nlohmann::json& corners = j.Raw("corners_px");
  const auto is_uv = [](const nlohmann::json& c) {
    return c.is_array() && c.size() == 2 && c[0].is_number() && c[1].is_number() &&
           std::isfinite(c[0].get<double>()) && std::isfinite(c[1].get<double>());
  };
  if (!corners.is_array() || corners.size() != 4 ||
      !std::all_of(corners.begin(), corners.end(), is_uv)) {
    j.Fail("corners_px", "expected 4 corners [u, v] of finite numbers");
    return t;
  }
  for (size_t k = 0; k < 4; ++k)
    t.corners_px[k] = {corners[k][0].get<double>(), corners[k][1].get<double>()};
  return t;
}

StoredCalibration::View ViewFromJson(const JsonObject& j, size_t cameras) {
  StoredCalibration::View view;
  view.view = static_cast<int>(j.Integer("view", {.min = 0, .max = kMaxIndex}));
  view.camera =
      static_cast<int>(j.Integer("camera", {.min = 0, .max = static_cast<int64_t>(cameras) - 1}));
  view.frame = j.StringOr("frame", "");
  view.solved = j.BoolOr("solved", false);
  if (!view.solved) {
    view.failure = j.StringOr("failure", "");
    return view;
  }
  view.cam_from_box = PoseField(j, "cam_from_box");
  view.cam_from_box_initial = PoseField(j, "cam_from_box_initial");
  view.cam_from_object = PoseField(j, "cam_from_object");
  view.rms_px = j.NumberOr("rms_px", 0.0, {.min = 0});
  view.uncertainty = UncertaintyFromJson(j.Raw("uncertainty"));
  if (j.Has("tags")) {
    for (const JsonObject& tag : j.Objects("tags")) view.tags.push_back(TagFromJson(tag));
  }
  return view;
}

const char* ModeName(CalibrationMode mode) {
  return mode == CalibrationMode::kTurntable ? "turntable" : "free";
}

nlohmann::json CalibrationJson(const CaptureCalibrationInput& input,
                               const CaptureCalibration& result) {
  nlohmann::json root;
  root["format"] = "hairrig-calibration";
  root["version"] = 1;
  root["mode"] = ModeName(result.mode);
  root["note"] =
      "a_from_b maps frame b to frame a; mm, px; pixel (0,0) is the centre of the top-left pixel. "
      "Object frame: turntable in turntable mode, box in free mode.";
  root["rms_px"] = result.rms_px;
  root["residual_sigma_px"] = result.residual_sigma_px;
  root["box"] = {{"file", input.box_source},
                 {"refined", result.box_refined},
                 {"sigma_as_given_px", result.sigma_box_as_given_px},
                 {"sigma_refined_px", result.sigma_box_refined_px}};
  root["converged"] = result.converged;
  root["iterations"] = result.iterations;
  if (result.mode == CalibrationMode::kTurntable)
    root["turntable_from_box"] = PoseToJson(result.turntable_from_box);
  root["cameras"] = nlohmann::json::array();
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    const CameraCalibration& cam = result.cameras[c];
    nlohmann::json j{{"name", input.cameras[c].name},
                     {"serial", input.cameras[c].serial},
                     {"solved", cam.solved}};
    if (!cam.solved) {
      j["failure"] = cam.failure;
    } else {
      j["intrinsics"] = IntrinsicsToJson(cam.intrinsics);
      j["intrinsics_initial"] = IntrinsicsToJson(cam.initial);
      j["intrinsics_source"] = cam.intrinsics_source;
      j["intrinsics_stddev"] = StddevJson(cam.intrinsics_stddev);
      if (result.mode == CalibrationMode::kTurntable)
        j["cam_from_world"] = PoseToJson(cam.cam_from_world);
    }
    root["cameras"].push_back(j);
  }
  root["views"] = nlohmann::json::array();
  const Rigid3d box_from_object = ObjectFromBox(result).Inverse();
  for (size_t f = 0; f < input.frames.size(); ++f) {
    const CalibrationFrame& in = input.frames[f];
    const FrameCalibration& frame = result.frames[f];
    nlohmann::json j{{"view", in.view},
                     {"camera", in.camera},
                     {"frame", in.name},
                     {"stop", in.stop},
                     {"turntable_deg", in.turntable_deg},
                     {"solved", frame.solved},
                     {"tags_detected", frame.tags_detected},
                     {"tags_used", frame.tags.size()}};
    if (frame.solved) {
      j["cam_from_box"] = PoseToJson(frame.cam_from_box);
      j["cam_from_box_initial"] = PoseToJson(frame.cam_from_box_init);
      j["cam_from_object"] = PoseToJson(frame.cam_from_box * box_from_object);
      j["rms_px"] = frame.rms_px;
      j["uncertainty"] = UncertaintyJson(frame.uncertainty);
      nlohmann::json tags = nlohmann::json::array();
      for (const TagObservation& tag : frame.tags) {
        nlohmann::json corners = nlohmann::json::array();
        for (const Eigen::Vector2d& c : tag.corners_px) corners.push_back({c.x(), c.y()});
        tags.push_back({{"id", tag.id}, {"corners_px", corners}});
      }
      j["tags"] = tags;
    } else {
      j["failure"] = frame.failure;
    }
    nlohmann::json rejected = nlohmann::json::array();
    for (const RejectedTag& r : frame.rejected)
      rejected.push_back({{"id", r.id}, {"reason", r.reason}});
    j["rejected_tags"] = rejected;
    root["views"].push_back(j);
  }
  return root;
}

std::string OpenCvYaml(const CameraIntrinsics& c) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "image_width" << c.width_px << "image_height" << c.height_px;
  fs << "camera_matrix"
     << (cv::Mat_<double>(3, 3) << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
  fs << "distortion_coefficients" << (cv::Mat_<double>(1, 5) << c.k1, c.k2, c.p1, c.p2, c.k3);
  return fs.releaseAndGetString();
}

// COLMAP's text model (colmap.github.io/format.html): camera ids from 1, model
// OPENCV (fx fy cx cy k1 k2 p1 p2), or FULL_OPENCV (... k3 k4 k5 k6) when k3 is used; an image line
// QW QX QY QZ TX TY TZ CAMERA_ID NAME with cam_from_object, then an empty line of 2D points.
void ColmapText(const CaptureCalibrationInput& input, const CaptureCalibration& result,
                std::string* cameras, std::string* images) {
  std::ostringstream cams, imgs;
  cams.precision(17);
  imgs.precision(17);
  cams << "# Camera list: CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[] (written by hairrig "
          "calibrate)\n";
  for (size_t c = 0; c < result.cameras.size(); ++c) {
    if (!result.cameras[c].solved) continue;
    const CameraIntrinsics& k = result.cameras[c].intrinsics;
    // COLMAP puts the centre of the top-left pixel at (0.5, 0.5), this project at (0, 0).
    cams << c + 1 << (k.k3 == 0 ? " OPENCV " : " FULL_OPENCV ") << k.width_px << " " << k.height_px
         << " " << k.fx_px << " " << k.fy_px << " " << k.cx_px + 0.5 << " " << k.cy_px + 0.5 << " "
         << k.k1 << " " << k.k2 << " " << k.p1 << " " << k.p2;
    if (k.k3 != 0) cams << " " << k.k3 << " 0 0 0";
    cams << "\n";
  }
  imgs << "# Image list: IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME, then POINTS2D "
          "(none)\n"
       << "# Images are in the capture's frames/ folder; poses are cam_from_object in mm.\n";
  const Rigid3d box_from_object = ObjectFromBox(result).Inverse();
  int id = 1;
  for (size_t f = 0; f < input.frames.size(); ++f) {
    if (!result.frames[f].solved) continue;
    const Rigid3d pose = result.frames[f].cam_from_box * box_from_object;
    const Eigen::Quaterniond& q = pose.rotation;
    imgs << id++ << " " << q.w() << " " << q.x() << " " << q.y() << " " << q.z() << " "
         << pose.translation.x() << " " << pose.translation.y() << " " << pose.translation.z()
         << " " << input.frames[f].camera + 1 << " "
         << fs::path(input.frames[f].name).filename().string() << "\n\n";
  }
  *cameras = cams.str();
  *images = imgs.str();
}

Status CreateFolder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return IoError(dir.string() + ": cannot create the folder (" + ec.message() + ")");
  return Status::Ok();
}

}  // namespace

Status WriteCalibration(const std::string& dir, const CaptureCalibrationInput& input,
                        const CaptureCalibration& result) {
  const fs::path root(dir);
  HR_RETURN_IF_ERROR(CreateFolder(root / "opencv"));
  HR_RETURN_IF_ERROR(CreateFolder(root / "colmap"));
  HR_RETURN_IF_ERROR(WriteFileAtomic((root / "calibration.json").string(),
                                     CalibrationJson(input, result).dump(1)));
  for (size_t c = 0; c < input.cameras.size(); ++c) {
    if (!result.cameras[c].solved) continue;
    const std::string file = (root / "opencv" / (input.cameras[c].serial + ".yaml")).string();
    HR_RETURN_IF_ERROR(WriteFileAtomic(file, OpenCvYaml(result.cameras[c].intrinsics)));
  }
  const fs::path box_file = root / "box_as_built.yaml";
  if (!result.box_refined) {
    // An earlier calibration's box is not this one's, unless it is the box
    // this calibration was given (`--exact-box --box` that file): kept.
    std::error_code ec;
    const bool given = !input.box_source.empty() && fs::equivalent(box_file, input.box_source, ec);
    if (!given) fs::remove(box_file, ec);
    if (ec && fs::exists(box_file))
      return IoError(box_file.string() + ": cannot remove (" + ec.message() + ")");
  } else {
    HR_RETURN_IF_ERROR(WriteCalibBox(
        result.box_as_built, box_file.string(),
        "The calibration box as built, refined with the cameras of this capture from\n" +
            (input.box_source.empty() ? std::string("the box it was given") : input.box_source) +
            " (standard deviations: *_sd_*). Give it to a later capture's calibration\n"
            "with `hairrig calibrate --box FILE`, or name it in the rig config's "
            "calibration.box."));
  }
  std::string cameras, images;
  ColmapText(input, result, &cameras, &images);
  HR_RETURN_IF_ERROR(WriteFileAtomic((root / "colmap" / "cameras.txt").string(), cameras));
  HR_RETURN_IF_ERROR(WriteFileAtomic((root / "colmap" / "images.txt").string(), images));
  return WriteFileAtomic((root / "colmap" / "points3D.txt").string(),
                         std::string("# 3D point list: none (poses from the calibration box)\n"));
}

Result<StoredCalibration> ReadCalibration(const std::string& calibration_json) {
  HR_ASSIGN_OR_RETURN(
      const nlohmann::json j,
      ReadJsonFile(calibration_json, "run `hairrig calibrate` on the capture first"));
  const JsonObject root(j, calibration_json);
  if (root.StringOr("format", "") != "hairrig-calibration" || root.IntegerOr("version", 0) != 1 ||
      !root.ok())
    return CorruptData(calibration_json + ": not a hairrig calibration of version 1");
  StoredCalibration out;
  out.mode = root.StringOr("mode", "");
  out.rms_px = root.NumberOr("rms_px", 0.0, {.min = 0});
  if (out.mode == "turntable") out.turntable_from_box = PoseField(root, "turntable_from_box");
  if (root.Has("box")) {
    const JsonObject box = root.Object("box");
    out.box_file = box.StringOr("file", "");
    out.box_refined = box.BoolOr("refined", false);
  }
  for (const JsonObject& camera : root.Objects("cameras"))
    out.cameras.push_back(CameraFromJson(camera));
  for (const JsonObject& view : root.Objects("views")) {
    out.views.push_back(ViewFromJson(view, out.cameras.size()));
    if (!root.ok()) break;
  }
  HR_RETURN_IF_ERROR(root.status());
  return out;
}

Status WriteIntrinsicsFile(const std::string& path, const std::string& serial,
                           const std::string& board, const ChArUcoCalibration& result) {
  nlohmann::json root{{"format", "hairrig-intrinsics"},
                      {"version", 1},
                      {"serial", serial},
                      {"board", board},
                      {"intrinsics", IntrinsicsToJson(result.intrinsics)},
                      {"intrinsics_stddev", StddevJson(result.stddev)},
                      {"rms_px", result.rms_px},
                      {"images_used", result.images_used}};
  root["images"] = nlohmann::json::array();
  for (const ChArUcoImage& image : result.images) {
    nlohmann::json j{{"path", image.path},
                     {"used", image.used},
                     {"markers", image.markers},
                     {"corners", image.corners}};
    if (image.used) j["rms_px"] = image.rms_px;
    if (!image.failure.empty()) j["failure"] = image.failure;
    root["images"].push_back(j);
  }
  return WriteFileAtomic(path, root.dump(1));
}

Status WriteMrcalCorners(const std::string& path, const ChArUcoBoard& board,
                         const ChArUcoCalibration& result) {
  std::string text = "# filename x y level\n";
  const size_t grid = board.corners_board_mm.size();
  for (const ChArUcoImage& image : result.images) {
    if (!image.used) continue;
    std::vector<const Eigen::Vector2d*> at(grid, nullptr);
    for (size_t k = 0; k < image.detected.ids.size(); ++k) {
      const size_t id = static_cast<size_t>(image.detected.ids[k]);
      if (id < grid) at[id] = &image.detected.corners_px[k];
    }
    const std::string name = std::filesystem::path(image.path).filename().string();
    for (const Eigen::Vector2d* c : at) {
      char line[64];
      if (c)
        std::snprintf(line, sizeof line, " %.4f %.4f 0\n", c->x(), c->y());
      else
        std::snprintf(line, sizeof line, " - - -\n");
      text += name + line;
    }
  }
  return WriteFileAtomic(path, text);
}

Result<std::vector<IntrinsicsPrior>> ReadIntrinsicsPriors(const std::string& path) {
  HR_ASSIGN_OR_RETURN(
      const nlohmann::json j,
      ReadJsonFile(path, "give a calibration.json or a file from `hairrig calibrate-intrinsics`"));
  const JsonObject root(j, path);
  if (root.StringOr("format", "") != "hairrig-intrinsics") {
    HR_RETURN_IF_ERROR(root.status());
    HR_ASSIGN_OR_RETURN(StoredCalibration calibration, ReadCalibration(path));
    std::vector<IntrinsicsPrior> priors;
    for (const StoredCalibration::Camera& camera : calibration.cameras) {
      if (camera.solved)
        priors.push_back({camera.serial, camera.intrinsics, camera.intrinsics_stddev, path});
    }
    return priors;
  }
  if (root.Integer("version") != 1 && root.ok())
    return CorruptData(path + ": hairrig-intrinsics of an unknown version");
  IntrinsicsPrior prior;
  prior.serial = root.String("serial");
  if (root.ok() && prior.serial.empty()) root.Fail("serial", "is empty");
  prior.intrinsics = IntrinsicsField(root, "intrinsics");
  prior.stddev = StddevField(root, "intrinsics_stddev");
  prior.source = path;
  HR_RETURN_IF_ERROR(root.status());
  return std::vector<IntrinsicsPrior>{prior};
}

}  // namespace hairrig
