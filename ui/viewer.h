// The look-dev viewer: a GLFW window with an OpenGL 3.3 core context and a Dear ImGui UI, showing a
// RenderSession's progressive image through the OCIO display pipeline. The frame loop follows Dear
// ImGui's GLFW/OpenGL3 example; rendering and loading never run on this (the UI) thread.
#pragma once

#include <string>
#include <vector>

namespace candela {

struct ViewerOptions {
  std::string scenePath;              // empty: the default scene (torch-in-mist)
  std::string preset;                 // --strategy: replaces the scene's strategy
  std::vector<std::string> settings;  // --set key=value edits
  std::string ocioConfig;             // --ocio: else $OCIO, else the shipped config
  int threads = 0;                    // render threads (0: all)
  int windowWidth = 1500, windowHeight = 820;

  // Scripted use (tests, batch): a screenshot once the image has `afterSpp` samples per pixel
  // (also the progress limit, so it is exact) or `afterSeconds` of rendering, then maybe quit.
  std::string screenshotPath;
  int afterSpp = 0;
  double afterSeconds = 0.0;
  bool quit = false;
  // Equal-time comparison (the talk's Fig. 1): one pane per strategy preset, side by side.
  std::vector<std::string> panes;
  double equalTime = 0.0;             // stop every pane at this many seconds (0: never)
  std::string figurePath;             // write the comparison figure once equalTime is reached
  std::string referencePath;          // reference EXR for the error series
  int referenceSpp = 0;               // else render (and cache) a reference at this spp
  std::string referenceStrategy = "emission";
  bool wipe = false;                  // two panes: one frame with a divider
  std::string paneView = "image";     // image | absolute | relative (error views need a reference)
  // Scripted edits to time edit-to-first-image and the UI frame rate while rendering.
  int measureEdits = 0;
  // Scripted edit applied once the first full frame is shown (a --set style key=value), to test
  // bad edits in the app.
  std::vector<std::string> editsAfterStart;
  // Then reset the camera (R), as an artist does after tumbling.
  bool resetCamera = false;
  // Open the guide inspector on this pixel once the first image is shown (as a Ctrl+click would);
  // a scripted screenshot then waits for its chart.
  std::vector<int> inspectPixel;
  // Opening a .vdb: its up axis (auto, y or z).
  std::string upAxis = "auto";
  // The document, scripted: undo / redo this many steps after the edits, then save to this path.
  int undoSteps = 0, redoSteps = 0;
  std::string saveAsPath;
  // Open this file as if it were dropped on the window, once the first scene is shown.
  std::string dropPath;
  // Apply the edits as soon as the dropped file starts loading, as an artist edits during a long load.
  bool editWhileLoading = false;
  // Hold every scene build back this many milliseconds: a long load, for tests.
  int holdBuildsMs = 0;
  // Keep a snapshot of the first image (at --after-spp), apply the edits, compare in the wipe view.
  bool snapshotCompare = false;
  // Step the timeline forward this many frames, timing each step's first image.
  int frameSteps = 0;
  // Press Play once the first image shows: each frame renders to the timeline's spp, then steps.
  bool play = false;
  // File > Open image, scripted: once the first image shows, this EXR becomes a snapshot compared
  // with the live render (in the comparison: the panes' reference).
  std::string openImagePath;
  // File > Render sequence, scripted: the timeline's frames (or the one shown) at --after-spp (else
  // the scene's spp) to this pattern, once the first image shows; quits when it ends with --quit.
  std::string renderSequencePattern;
  // A render region, scripted (x, y, width, height in pixels), set once the first image shows.
  std::vector<int> region;
};

// Runs the viewer until the window closes (or a scripted --quit). Returns the process exit code.
int runViewer(const ViewerOptions& options);

}  // namespace candela
