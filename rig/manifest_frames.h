// The frames of a capture folder as every stage after capture reads them
// (calibrate, reconstruct and their batch stages): manifest.json's frame list,
// each frame checked against its record before anything decodes it.
//
//   HR_ASSIGN_OR_RETURN(std::vector<ManifestFrame> frames, ReadManifestFrames(capture_dir));
//   HR_RETURN_IF_ERROR(VerifyManifestFrames(capture_dir, &frames));
//   for (const ManifestFrame& f : frames)
//     if (f.unusable.empty()) Use(f.path); else LeaveOut(f.file, f.unusable);
//
// A frame is usable only when its file, resolved with its symlinks, stays
// inside the capture folder, is a regular file and has the byte count and
// SHA-256 its record gives (rig/capture_dataset.h VerifyFrameFile). A frames/
// folder that leads outside the capture folder refuses the whole capture.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"

namespace hairrig {

// One entry of manifest.json's "frames" (the frame_stored record it was
// derived from), with the outcome of checking its file.
struct ManifestFrame {
  std::string record;  // names the entry in messages: "<capture>/manifest.json: field 'frames[3]'"
  // Names its serial in messages: "<capture>/manifest.json: field 'frames[3].serial'".
  std::string serial_field;
  int view = 0;
  int stop = 0;
  double angle_measured_deg = 0;  // the turntable's encoder, deg
  std::string serial;
  std::string file;  // relative to the capture folder: FrameFileName(view, serial, extension)
  // <capture_dir>/<file>, lexically normalised; once VerifyManifestFrames
  // verified the file, the path with its symlinks resolved (the file that was
  // checked, so the one to read).
  std::string path;
  uint64_t bytes = 0;
  std::string sha256;
  // Empty when the file verifies; else why not, naming the file (a changed,
  // missing or truncated frame, one leading outside the capture folder) and
  // how to get it back.
  std::string unusable;
};

// FailedPrecondition naming <capture_dir>/frames and where it leads when it
// resolves (through a symlink) to a folder outside the capture folder; IoError
// when it cannot be resolved; Ok when it stays inside or does not exist.
Status CheckFramesFolder(const std::string& capture_dir);

// The frames manifest.json lists, in its order, checked as records: no file
// is read (every `unusable` is empty). CorruptData naming manifest.json and
// the field for a missing or mistyped field, a view listed twice (refused at
// the first repeat), a file other than the view's and camera's FrameFileName,
// two views with the same SHA-256 (a frame and its entry copied onto another
// view, refused as resume refuses it: rig/capture_dataset.h
// CheckDistinctContent); NotFound for a missing manifest.json.
Result<std::vector<ManifestFrame>> ReadManifestFrames(const std::string& capture_dir);

// Checks each frame's file against its record (VerifyFrameFile): sets
// `unusable` for a file that does not verify; clears it for one that does and
// sets `path` to the file VerifyFrameFile checked.
// CheckFramesFolder's error refuses the whole capture before any frame is read.
Status VerifyManifestFrames(const std::string& capture_dir, std::vector<ManifestFrame>* frames);

}  // namespace hairrig
