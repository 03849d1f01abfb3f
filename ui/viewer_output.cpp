// What the viewer writes: screenshots (the PNG as displayed, through OCIO, and the scene-linear EXR
// with variance and spp layers) and comparison figures.
#include "viewer_impl.h"

#include "atomic_file.h"
#include "error_chart.h"

#include <ctime>
#include <fstream>

namespace candela {

namespace fs = std::filesystem;

namespace {
// A pane's label as part of a file name: "full*" (edited) becomes "full-edited".
std::string paneFileLabel(std::string label) {
  if (!label.empty() && label.back() == '*') label = label.substr(0, label.size() - 1) + "-edited";
  for (char& c : label)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '-';
  return label;
}
}  // namespace

bool Viewer::writeFigure(const std::string& path) {
  if (!compFrame_ || compFrame_->panes.empty()) {
    report("figure: nothing to compare yet");
    return false;
  }
  figureRequest_ = path.empty() ? freshPath(fs::path("screenshots") / (fs::path(scenePath_).stem().string() + "-comparison.png")) : path;
  return true;
}

// Which snapshot the live render is compared with, and how (nothing when none is).
void Viewer::addComparisonMetadata(std::map<std::string, std::string>& meta) const {
  const Snapshot* snap = comparedSnapshot_ ? snapshots_.find(comparedSnapshot_) : nullptr;
  if (!snap) return;
  meta["compared_snapshot"] = snap->label;
  meta["compare_mode"] = canvas_.wipe() ? "wipe" : "side by side";
  meta["wipe_position"] = std::to_string(canvas_.wipePosition());
}

// The image area of the frame just drawn (before the swap), as the window shows it.
DisplayImage Viewer::readCanvas() const {
  const auto [x, y, w, h] = canvas_.framebufferRect(canvas_.rect());
  DisplayImage image;
  image.width = w;
  image.height = h;
  std::vector<uint8_t> rows(3 * static_cast<size_t>(w) * h);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(x, y, w, h, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
  image.rgb8.resize(rows.size());
  for (int row = 0; row < h; ++row)  // GL reads bottom-up
    std::copy_n(rows.begin() + 3 * static_cast<size_t>(h - 1 - row) * w, 3 * static_cast<size_t>(w),
                image.rgb8.begin() + 3 * static_cast<size_t>(row) * w);
  return image;
}

// Reads the panes and their labels back from the frame just drawn (before the swap): the figure is
// what the window shows. Writes PATH.png, one EXR per pane and the error series as CSV.
void Viewer::captureFigure() {
  const std::string path = *figureRequest_;
  figureRequest_.reset();
  try {
    DisplayImage image = readCanvas();
    Json panes = Json::array();
    for (const auto& p : compFrame_->panes) {
      Json j{{"label", p.label}, {"title", paneTitle(p)}, {"seconds", p.seconds}, {"last_slice_seconds", p.lastSlice}, {"spp", p.film ? p.film->spp() : 0}, {"strategy", toJson(p.strategy)}};
      if (!p.series.empty())
        j["relmse"] = p.series.back().relmse, j["mse"] = p.series.back().mse, j["efficiency"] = p.efficiency(),
        j["error_estimated"] = p.series.back().estimated;
      if (!p.autoSummary.empty()) j["auto_decision"] = p.autoSummary;
      if (p.agreementTested) j["agrees"] = p.agreement.agree;
      panes.push_back(j);
    }
    image.metadata["scene"] = scenePath_;
    image.metadata["panes"] = panes.dump();
    // How the panes sit in the figure: row by row in a grid of columns x rows.
    image.metadata["grid"] = std::to_string(canvas_.columns()) + "x" + std::to_string(canvas_.rows());
    image.metadata["settings"] = sceneToJson(edited_).dump();
    image.metadata["display"] = toJson(colors_.resolve(display_)).dump();
    image.metadata["document"] = documentPath_;
    if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
    writeDisplayPng(path, image);
    const fs::path stem = fs::path(path).replace_extension("");
    for (const auto& p : compFrame_->panes) {
      if (!p.film) continue;
      Image exr;
      exr.width = p.film->width();
      exr.height = p.film->height();
      exr.rgb = p.film->meanImage();
      exr.metadata = {{"scene", scenePath_}, {"strategy", toJson(p.strategy).dump()}, {"spp", std::to_string(p.film->spp())},
                      {"time_s", std::to_string(p.seconds)}};
      const std::string paneStem = stem.string() + "-" + paneFileLabel(p.label);
      writeExr(paneStem + ".exr", exr);
      // The pane as displayed (through OCIO, at the film's resolution).
      const size_t i = static_cast<size_t>(&p - compFrame_->panes.data());
      if (i < paneGl_.size() && paneGl_[i]->outputWidth() > 0) {
        DisplayImage png;
        png.width = paneGl_[i]->outputWidth();
        png.height = paneGl_[i]->outputHeight();
        png.rgb8 = paneGl_[i]->readOutput();
        png.metadata = exr.metadata;
        png.metadata["pane"] = paneTitle(p);
        png.metadata["display"] = toJson(colors_.resolve(display_)).dump();
        writeDisplayPng(paneStem + ".png", png);
      }
    }
    writeTextAtomically(stem.string() + ".csv", comparisonCsv(*compFrame_));
    report("figure: wrote " + path + ", a PNG and an EXR per pane and " + stem.string() + ".csv");
    figureDone_ = true;
  } catch (const std::exception& e) {
    report(std::string("figure failed: ") + e.what());
    exitCode_ = 1;
    figureDone_ = true;
  }
}

bool Viewer::screenshot(const std::string& requestedPath) {
  // The comparison: the figure as the window shows it, with every pane's PNG and EXR beside it.
  if (compare_) return writeFigure(requestedPath);
  if (!frame_ || !gl_->outputWidth()) {
    report("screenshot: no image yet");
    return false;
  }
  std::string pngPath = requestedPath;
  if (pngPath.empty()) {
    const std::time_t now = std::time(nullptr);
    char stamp[32];
    std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", std::localtime(&now));
    const std::string stem = fs::path(scenePath_).stem().string();
    pngPath = freshPath(fs::path("screenshots") / (stem + "-" + stamp + ".png"));
  }
  const std::string exrPath = fs::path(pngPath).replace_extension(".exr").string();
  try {
    if (fs::path(pngPath).has_parent_path()) fs::create_directories(fs::path(pngPath).parent_path());
    std::map<std::string, std::string> meta;
    meta["scene"] = scenePath_;
    // What the GUI tests check besides the pixels: the document, its state and what is compared.
    meta["document"] = documentPath_;
    meta["unsaved_edits"] = dirty_ ? "yes" : "no";
    meta["undo_steps"] = std::to_string(history_.undoSteps());
    meta["redo_steps"] = std::to_string(history_.redoSteps());
    meta["frame"] = std::to_string(edited_.render.frame);
    if (!frames_.empty()) meta["frames"] = std::to_string(frames_.first) + "-" + std::to_string(frames_.last);
    addComparisonMetadata(meta);
    if (!importSummary_.empty()) meta["opened_volume"] = importSummary_;
    if (!frame_->autoDecision.empty()) meta["auto_decision"] = frame_->autoDecision;
    if (!frame_->adaptiveSplit.empty()) meta["adaptive_split"] = frame_->adaptiveSplit;
    if (frame_->scene) {
      meta["strategy"] = toJson(frame_->scene->strategy).dump();
      SceneDesc shown = *frame_->scene;
      shown.display = display_;
      meta["settings"] = sceneToJson(shown).dump();
    }
    meta["display"] = toJson(colors_.resolve(display_)).dump();
    meta["ocio_config"] = colors_.configPath();
    meta["spp"] = std::to_string(frame_->preview ? 0 : frame_->film.spp());
    meta["time_s"] = std::to_string(frame_->seconds);
    meta["rejected_samples"] = std::to_string(frame_->film.rejectedSamples());
    if (frame_->region && frame_->regionFilm.spp() > 0) {
      meta["region"] = std::to_string(frame_->region->x) + "," + std::to_string(frame_->region->y) + "," +
                       std::to_string(frame_->region->w) + "," + std::to_string(frame_->region->h);
      meta["region_spp"] = std::to_string(frame_->regionFilm.spp());
    }
    DisplayImage png;
    png.width = gl_->outputWidth();
    png.height = gl_->outputHeight();
    png.rgb8 = gl_->readOutput();
    png.metadata = meta;
    writeDisplayPng(pngPath, png);
    Image exr;
    exr = frame_->film.image();  // with the variance and spp layers
    // As shown: the region's pixels from its own film (the layers stay the rest of the image's).
    if (frame_->region && frame_->regionFilm.spp() > 0) exr.rgb = frame_->shownImage();
    exr.metadata = meta;
    writeExr(exrPath, exr);
    report("screenshot: wrote " + pngPath + " and " + exrPath);
    // Comparing a snapshot: also the canvas as shown (live | snapshot), read back before the swap.
    if (comparedSnapshot_) canvasCaptureRequest_ = fs::path(pngPath).replace_extension("").string() + "-compare.png";
    return true;
  } catch (const std::exception& e) {
    report(std::string("screenshot failed: ") + e.what());
    return false;
  }
}

void Viewer::captureCanvas() {
  const std::string path = *canvasCaptureRequest_;
  canvasCaptureRequest_.reset();
  try {
    DisplayImage image = readCanvas();
    addComparisonMetadata(image.metadata);
    writeDisplayPng(path, image);
    report("canvas: wrote " + path);
  } catch (const std::exception& e) {
    report(std::string("canvas capture failed: ") + e.what());
  }
}

}  // namespace candela
