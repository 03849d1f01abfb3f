// candela: the look-dev viewer.
//   candela [SCENE.json | VOLUME.vdb [--up auto|y|z]] [--strategy PRESET] [--set key=value ...] [--ocio CONFIG] [--threads N]
//           [--screenshot OUT.png (--after SECONDS | --after-spp N)] [--quit]
//           [--measure-latency N] [--edit key=value ...]
//           [--panes P1,P2,... [--equal-time SECONDS] [--figure OUT.png] [--reference REF.exr | --reference-spp N]]
#include "cli_checks.h"
#include "input_limits.h"
#include "settings.h"
#include "viewer.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>

int main(int argc, char** argv) {
  candela::ViewerOptions o;
  CLI::App app{"Candela look-dev viewer: progressive volume path tracing with live edits and OCIO display"};
  app.add_option("scene", o.scenePath,
                 "Scene JSON, or a .vdb to open as a volume: grids recognised by name, framed, lit by a sun and sky, auto exposure "
                 "(default: the talk's Fig. 1 live: assets/scenes/torch-in-mist.json in four equal-time panes, conventional, "
                 "emission, full and auto)");
  app.add_option("--up", o.upAxis, "Opening a .vdb: its up axis, auto (Z when Blender wrote it, else Y), y or z")
      ->check(CLI::IsMember({"auto", "y", "z"}));
  std::string presets;
  for (const auto& n : candela::strategyPresetNames()) presets += (presets.empty() ? "" : ", ") + n;
  app.add_option("--strategy", o.preset, "Strategy preset replacing the scene's: " + presets);
  app.add_option("--set", o.settings, "Edit a scene field before loading, e.g. --set volumes.0.g=0.5");
  app.add_option("--ocio", o.ocioConfig, "OCIO config (default: $OCIO, else assets/ocio/config.ocio)");
  app.add_option("--threads", o.threads, "Render threads (0: all)")->check(CLI::NonNegativeNumber);
  app.add_option("--size", o.windowWidth, "Window width in pixels")->check(CLI::Range(320, 8192));
  app.add_option("--screenshot", o.screenshotPath,
                 "Write a screenshot (PNG as displayed + scene-linear EXR) to this path; in the comparison, the figure plus a PNG and "
                 "an EXR per pane");
  auto after = app.add_option("--after", o.afterSeconds, "Screenshot after this many seconds of rendering")->check(candela::finitePositive());
  app.add_option("--after-spp", o.afterSpp,
                 "Screenshot at exactly this many samples per pixel (also stops there); in the comparison, once every pane has as many")
      ->check(candela::finitePositive())
      ->excludes(after);
  app.add_flag("--quit", o.quit, "Quit after the screenshot (or at once when there is none)");
  app.add_option("--measure-latency", o.measureEdits, "Make N scripted edits and print edit-to-first-image latency and UI fps")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--inspect", o.inspectPixel, "Open the guide inspector on pixel X,Y once the first image is shown (Ctrl+click does it live)")
      ->delimiter(',')
      ->expected(2);
  app.add_option("--edit", o.editsAfterStart, "Apply a key=value edit once the first image is shown (as if typed in the panel)");
  app.add_flag("--reset-camera", o.resetCamera, "Scripted: press Reset camera (R) after the --edit edits");
  app.add_option("--undo", o.undoSteps, "Scripted: undo this many edits after the --edit edits")->check(CLI::NonNegativeNumber);
  app.add_option("--redo", o.redoSteps, "Scripted: then redo this many")->check(CLI::NonNegativeNumber);
  app.add_option("--save-as", o.saveAsPath, "Scripted: then save the scene (with every edit) to this JSON file");
  app.add_option("--drop", o.dropPath, "Scripted: open this file as if dropped on the window, once the first scene shows");
  app.add_flag("--edit-while-loading", o.editWhileLoading,
               "Scripted: apply the --edit edits as soon as the --drop file starts loading (an artist editing during a long load)");
  app.add_option("--hold-builds", o.holdBuildsMs, "Scripted: hold every scene build back this many milliseconds (a long load, for tests); with --edit-while-loading, the dropped file's build also waits for the scripted edits")
      ->check(CLI::Range(0, 60000));
  app.add_flag("--snapshot-compare", o.snapshotCompare,
               "Scripted: snapshot the image at --after-spp, apply the --edit edits, compare the live render with it in the wipe view");
  app.add_option("--frame-steps", o.frameSteps, "Scripted: step the timeline this many frames, timing each frame's first image")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--play", o.play, "Scripted: press Play once the first image shows (each frame renders to the timeline's spp, 16, then steps); a screenshot waits for the first step to another frame (or a pause), and Play is pressed again before it");
  app.add_option("--open-image", o.openImagePath,
                 "Scripted: File > Open image once the first image shows: an EXR kept as a snapshot and compared with the live render "
                 "(in the comparison: the panes' reference)");
  app.add_option("--render-sequence", o.renderSequencePattern,
                 "Scripted: File > Render sequence once the first image shows: the timeline's frames at --after-spp (else the scene's "
                 "spp) to this pattern (OUT.####.exr or .png)");
  app.add_option("--region", o.region, "Scripted: a render region X,Y,W,H (pixels) once the first image shows (Ctrl+drag does it live)")
      ->delimiter(',')
      ->expected(4);
  std::string panes;
  app.add_option("--panes", panes, "Equal-time comparison: comma-separated strategy presets, one pane each (1 to 4)");
  app.add_option("--equal-time", o.equalTime, "Stop every pane after this many seconds of rendering")->check(candela::finitePositive());
  app.add_option("--figure", o.figurePath, "Write the comparison figure (PNG, one EXR per pane, CSV) once --equal-time is reached");
  app.add_option("--reference", o.referencePath, "Reference EXR for the panes' error series");
  app.add_option("--reference-spp", o.referenceSpp, "Else render a reference at this spp (cached on disk)")->check(candela::finitePositive());
  app.add_option("--reference-strategy", o.referenceStrategy, "Strategy preset of the rendered reference (default emission)");
  app.add_flag("--wipe", o.wipe, "With two panes: show them in one frame split by a draggable divider");
  app.add_option("--pane-view", o.paneView, "What the panes show: image, absolute or relative (error against the reference)")
      ->check(CLI::IsMember({"image", "absolute", "relative"}));
  double maxMemoryGb = 0.0;
  app.add_option("--max-memory", maxMemoryGb,
                 "Memory budget in GB for any one input-sized structure (film, grid, probes); default 4 or CANDELA_MAX_MEMORY_GB")
      ->check(candela::finitePositive());
  CLI11_PARSE(app, argc, argv);
  try {
    candela::checkMemoryBudgetEnvironment();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "candela: %s\n", e.what());
    return 2;
  }
  if (maxMemoryGb > 0.0) candela::setMemoryBudgetBytes(static_cast<size_t>(maxMemoryGb * 1073741824.0));
  for (size_t start = 0; start < panes.size();) {
    const size_t comma = std::min(panes.find(',', start), panes.size());
    if (comma > start) o.panes.push_back(panes.substr(start, comma - start));
    start = comma + 1;
  }
  if (o.panes.size() > 4) {
    std::fprintf(stderr, "candela: --panes: expected 1 to 4 strategies, got %zu\n", o.panes.size());
    return 2;
  }
  for (const auto& p : o.panes)
    if (std::find(candela::strategyPresetNames().begin(), candela::strategyPresetNames().end(), p) == candela::strategyPresetNames().end()) {
      std::fprintf(stderr, "candela: --panes: unknown strategy preset \"%s\" (expected one of %s)\n", p.c_str(), presets.c_str());
      return 2;
    }
  // No scene and no other mode: the talk's Fig. 1 live, conventional | + emission | + scattering (MIS),
  // and beside them what Candela chooses by itself (auto, the default for the artist's own scenes).
  // A screenshot, --after and --quit keep it (the screenshot is the figure and every pane); a preset
  // or a flag that works on one view opens the default scene alone, and says so.
  if (o.scenePath.empty() && o.panes.empty() && o.preset.empty()) {
    std::string single;
    if (o.measureEdits > 0) single = "--measure-latency";
    else if (!o.dropPath.empty()) single = "--drop";
    else if (!o.editsAfterStart.empty()) single = "--edit";
    else if (!o.inspectPixel.empty()) single = "--inspect";
    else if (!o.saveAsPath.empty()) single = "--save-as";
    else if (o.snapshotCompare) single = "--snapshot-compare";
    else if (o.frameSteps > 0 || o.play) single = o.play ? "--play" : "--frame-steps";
    else if (o.undoSteps > 0 || o.redoSteps > 0 || o.resetCamera) single = "--undo/--redo/--reset-camera";
    if (single.empty())
      o.panes = {"conventional", "emission", "full", "auto"};
    else
      std::fprintf(stderr, "candela: %s works on one view: opening the default scene alone (name a scene, or --panes, to choose)\n",
                   single.c_str());
  }
  if (!o.figurePath.empty() && (o.panes.empty() || o.equalTime <= 0.0)) {
    std::fprintf(stderr, "candela: --figure needs --panes and --equal-time\n");
    return 2;
  }
  o.windowHeight = o.windowWidth * 820 / 1500;
  return candela::runViewer(o);
}
