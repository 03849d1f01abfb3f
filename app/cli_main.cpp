// candela-cli: batch rendering, equal-time benchmarking and volume generation.
//   candela-cli render SCENE.json|VOLUME.vdb -o OUT.exr|OUT.png [--spp N | --time S] [--seed N] [--threads N] [--up auto|y|z] [--frames A-B]
//                      [--strategy PRESET] [--set key=value ...]
//   candela-cli bench SCENE.json --strategies A,B --times T1,T2 [--reference REF.exr | --reference-spp N] -o DIR
//                     [--sweep KEY=V1,V2,...]
//   candela-cli generate TYPE -o OUT.vdb [--seed N] [--resolution N] [--size X,Y,Z] [--value V] [--temperature T]
#include "atomic_file.h"
#include "auto_strategy.h"
#include "cli_checks.h"
#include "convergence.h"
#include "guide_inspector.h"
#include "input_limits.h"
#include "procedural.h"
#include "renderer.h"
#include "scene.h"
#include "sequence.h"
#include "vdb_import.h"

#include "report.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numeric>
#include <optional>
#include <fstream>
#include <sstream>

using namespace candela;

namespace {

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

// The scene document with a strategy preset (if any) and the --set edits applied, validated.
SceneDesc sceneWith(const std::string& path, const std::string& preset, const std::vector<std::string>& sets) {
  SceneDesc desc = loadSceneDesc(path, sets, preset);
  // An edited strategy is the user's, not auto's to decide (needsAutoResolve): it renders as edited,
  // with no pilot, under the name auto. Say so, or a sweep over strategy.* reads like auto's figures.
  if (desc.strategy.preset == "auto" && !needsAutoResolve(desc.strategy))
    std::cerr << "warning: " << path << ": strategy \"auto\" with edited strategy fields (--set strategy.* or the scene's strategy "
              << "block) renders those settings as they are, without auto's rules or pilot; edit a preset instead (e.g. --strategy "
              << "emission)\n";
  return desc;
}

std::shared_ptr<Scene> buildScene(const SceneDesc& desc) {
  std::vector<std::string> warnings;
  auto scene = Scene::build(desc, &warnings);
  for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
  if (const AutoDecision* d = scene->autoDecision()) {
    std::printf("%s (%.2f s)\n", d->summary().c_str(), d->pilotSeconds);
    if (std::getenv("CANDELA_VERBOSE"))
      for (const auto& m : d->pilot)
        std::printf("  pilot %-24s relative variance %.4g  variance %.4g  work per sample %.0f  score %.3f\n", m.name.c_str(),
                    m.relativeVariance, m.absoluteVariance, m.workPerSample, m.efficiency);
  }
  if (auto probes = scene->probes())
    std::printf("probes: %zu learned of %d placed (spacing %.3g, radius %.3g) in %.2f s%s\n", probes->probes().size(), probes->placed(),
                probes->spacing(), probes->radius(), probes->learnSeconds(), probes->complete() ? "" : " (CUT BY THE TIME CAP)");
  return scene;
}

// Renders `desc` and writes `out`; returns the render seconds. A PNG is display-referred: the scene's
// exposure, or when it gives none (an opened VDB, a scene without display.exposure) auto exposure
// from this image, decided once for a sequence: `sequenceExposure` carries the first frame's choice
// to the others, so the frames do not flicker.
double renderOne(const SceneDesc& desc, const std::string& scenePath, const std::string& out, int threads, bool quiet,
                 std::optional<float>* sequenceExposure = nullptr) {
  const auto loadStart = std::chrono::steady_clock::now();
  auto scene = buildScene(desc);
  const double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - loadStart).count();
  ProgressiveRenderer renderer(scene, RenderOptions{threads, 32});
  // auto's pilot samples, when it piloted this image itself, are the render's first samples.
  Film film = continueFromPilot(*scene, desc.render.spp);
  const double t = renderer.renderBudget(film, desc.render.spp, desc.render.time_s, desc.render.time_s > 0 ? 1 : 4);
  Image image = film.image();  // with variance and spp layers in the EXR
  image.metadata["scene"] = scenePath;
  image.metadata["settings"] = sceneToJson(desc).dump();
  image.metadata["spp"] = std::to_string(film.spp());
  image.metadata["seconds"] = std::to_string(t);
  image.metadata["frame"] = std::to_string(desc.render.frame);
  if (const AutoDecision* d = scene->autoDecision()) image.metadata["auto_decision"] = d->summary();
  if (const SplitMap* split = renderer.adaptiveSplit()) image.metadata["adaptive_split"] = split->summary();
  image.metadata["rejected_samples"] = std::to_string(film.rejectedSamples());
  float exposure = desc.display.exposure;
  if (desc.display.autoExposure) {
    if (sequenceExposure && *sequenceExposure) exposure = **sequenceExposure;
    else exposure = autoExposureStops(image.rgb);
    if (sequenceExposure) *sequenceExposure = exposure;
  }
  image.metadata["exposure"] = std::to_string(exposure);
  const std::filesystem::path parent = std::filesystem::path(out).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  std::string extension = std::filesystem::path(out).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".png")
    writePng(out, image, exposure);
  else
    writeImage(out, image);
  if (!quiet) {
    const double paths = static_cast<double>(film.spp()) * film.width() * film.height();
    // Auto is charged its pilot, as bench charges it: the pilot's work over every sample in the
    // image (the pilot's kept samples included), so relative variance x work compares it with a
    // preset per sample.
    const AutoDecision* decision = scene->autoDecision();
    const double work = renderer.work().cost() + (decision ? decision->pilotWork : 0.0);
    // Per film sample: a split pixel's film sample is the mean of several camera samples, and its
    // variance and its work are both per film sample (sample_allocation.h).
    const double samples = paths;
    std::printf("%s: %dx%d, %d spp, strategy %s, load %.2f s, render %.2f s, %.3g samples/s, %llu rejected samples, "
                "relative variance per sample %.4g, variance per sample %.4g, work per sample %.4g%s\n",
                scenePath.c_str(), film.width(), film.height(), film.spp(), desc.strategy.preset.c_str(), loadSeconds, t,
                paths / std::max(t, 1e-9), static_cast<unsigned long long>(film.rejectedSamples()), relativeVariancePerSample(film),
                variancePerSample(film), work / std::max(1.0, samples), decision ? " (the pilot's included)" : "");
    if (const SplitMap* split = renderer.adaptiveSplit()) std::printf("%s\n", split->summary().c_str());
    // Where the work went, per camera sample (CANDELA_VERBOSE): the counts work.h prices.
    if (std::getenv("CANDELA_VERBOSE")) {
      const WorkCounters& w = renderer.work();
      const double n = std::max(1.0, static_cast<double>(w.samples));
      std::printf("work per sample by kind: collisions %.2f, segments %.2f, rays %.2f, knots %.2f, guided %.3f, guides %.3f\n",
                  w.collisions / n, w.segments / n, w.rays / n, w.knots / n, w.guided / n, w.guides / n);
      if (const CameraGuides& guides = renderer.cameraGuides(); guides.bytes() > 0) {
        const std::vector<size_t> byProbability = guides.pixelsByProbability();  // every pixel with a table, by q
        const size_t tables = std::accumulate(byProbability.begin(), byProbability.end(), size_t{0});
        std::printf("camera-ray tables: %zu of %d pixels, %.2f MB with the guide entries\n", tables, film.width() * film.height(),
                    static_cast<double>(guides.bytes()) / 1e6);
      }
      if (const CameraGuides& guides = renderer.cameraGuides(); guides.measuredDecisions() > 0) {
        const std::vector<size_t> counts = guides.pixelsByProbability();
        std::printf("measured q (%zu decisions), pixels:", guides.measuredDecisions());
        for (size_t c = 0; c < CameraGuides::kMeasuredProbabilities.size(); ++c)
          std::printf(" %g: %zu", CameraGuides::kMeasuredProbabilities[c], counts[c]);
        std::printf("\n");
      }
      for (const Medium* m : scene->media().media) {
        const glm::ivec3 r = m->majorantGrid().resolution();
        std::printf("majorant of %s: %dx%dx%d cells (%dx cell_size)\n", m->desc().name.c_str(), r.x, r.y, r.z, m->majorantCoarsening());
      }
    }
    std::printf("wrote %s\n", std::filesystem::absolute(out).string().c_str());
  }
  if (const std::string w = film.rejectedSamplesWarning(); !w.empty()) std::fprintf(stderr, "warning: %s: %s\n", scenePath.c_str(), w.c_str());
  return loadSeconds + t;
}

int render(const std::string& scenePath, const std::string& out, int spp, double seconds, int seed, int threads,
           const std::string& preset, const std::vector<std::string>& sets, const VdbImportOptions& import, const std::string& framesText) {
  std::vector<std::string> all = sets;
  if (seed >= 0) all.insert(all.begin(), "render.seed=" + std::to_string(seed));
  VdbImportReport imported;
  SceneDesc desc = loadSceneOrVdb(scenePath, all, preset, import, &imported);
  if (isVdbPath(scenePath)) std::printf("%s: opened as a volume: %s\n", scenePath.c_str(), imported.summary().c_str());
  if (isVdbPath(out)) throw InputError(out + ": expected an output image (.exr or .png), got a .vdb");
  if (spp > 0) desc.render.spp = spp;
  if (seconds > 0.0) desc.render.time_s = static_cast<float>(seconds);
  else if (spp > 0) desc.render.time_s = 0.0f;
  if (framesText.empty()) {
    renderOne(desc, scenePath, out, threads, false);
    return 0;
  }
  // A numbered sequence: OUT's own pattern (out.####.exr), else .#### before the extension.
  const FrameRange range = parseFrameRange(framesText, "--frames");
  const int first = range.first, last = range.last;
  // A range past the sequence on disk is a mistyped range, not frames to pass one by one (1-100000
  // over 48 files would print 99,952 errors): said at once, with the range there is.
  const FrameRange onDisk = sceneFrames(desc);
  if (!onDisk.empty() && (first < onDisk.first || last > onDisk.last))
    throw InputError("--frames " + framesText + ": the sequence on disk runs from frame " + std::to_string(onDisk.first) + " to " +
                     std::to_string(onDisk.last) + " (" + std::to_string(onDisk.count) + " files)");
  std::string pattern = out;
  if (!hasFramePattern(out)) {
    const std::filesystem::path p(out);
    pattern = (p.parent_path() / (p.stem().string() + ".####" + p.extension().string())).string();
  }
  const int count = last - first + 1;
  const auto start = std::chrono::steady_clock::now();
  // A frame whose files cannot be read (a missing or truncated sim frame) is reported and passed: the
  // other frames of a long batch still render, and the exit status says some did not.
  std::vector<int> failed;
  std::optional<float> exposure;  // the first rendered frame's auto exposure, kept for the rest
  for (int f = first; f <= last; ++f) {
    SceneDesc frame = desc;
    frame.render.frame = f;
    const std::string path = substituteFrame(pattern, f);
    try {
      renderOne(frame, scenePath, path, threads, true, &exposure);
    } catch (const InputError& e) {
      std::fprintf(stderr, "\nerror: frame %d: %s (going on with the next frame)\n", f, e.what());
      // A frame an earlier run wrote stays as it was (outputs are replaced only when complete), but it
      // is not this run's: said, so that a full folder does not read as a finished run.
      if (std::filesystem::exists(path))
        std::fprintf(stderr, "error: frame %d: %s is from an earlier run, not this one\n", f, path.c_str());
      failed.push_back(f);
      continue;
    }
    // A progress bar on stderr (stdout stays one line per frame, for logs).
    const int done = f - first + 1;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int width = 30, filled = done * width / count;
    std::fprintf(stderr, "\r[%s%s] %d/%d frames, %.1f s elapsed, %.1f s left ", std::string(static_cast<size_t>(filled), '#').c_str(),
                 std::string(static_cast<size_t>(width - filled), '.').c_str(), done, count, elapsed, elapsed / done * (count - done));
    std::printf("frame %d: wrote %s\n", f, std::filesystem::absolute(path).string().c_str());
    std::fflush(stdout);
  }
  std::fprintf(stderr, "\n");
  if (!failed.empty()) {
    std::string list;
    for (int f : failed) list += (list.empty() ? "" : ", ") + std::to_string(f);
    std::fprintf(stderr, "error: %zu of %d frames could not be rendered (frames %s; the errors above say why); the others were written\n",
                 failed.size(), count, list.c_str());
    return 2;
  }
  return 0;
}

// Fits WorkCounters::cost()'s constants: time of 4-spp passes at 160x90 on one thread against the
// counted work, over the report scenes and strategies, by least squares (non-negative).
int calibrate() {
  const std::string assets = std::string(CANDELA_SOURCE_DIR) + "/assets/scenes/";
  constexpr int kTerms = 7;  // WorkCounters' fields, in cost()'s order
  struct Row {
    double x[kTerms];
    double seconds;
  };
  std::vector<Row> rows;
  for (const char* name : {"torch-in-mist", "torch-in-fog", "fire", "god-rays", "god-rays-backlit", "god-rays-dark", "cloud", "test/glow-box"}) {
    // full guides continuations in the sun-lit scenes, so its rows cover their knots and guided vertices.
    for (const char* preset : {"conventional", "emission", "full", "equiangular"}) {
      SceneDesc desc = loadSceneDesc(assets + name + ".json");
      desc.strategy = strategyPreset(preset);
      desc.camera.resolution = {160, 90};
      auto scene = Scene::build(desc);
      ProgressiveRenderer renderer(scene, RenderOptions{1, 16});
      Film film;
      renderer.renderPass(film, 1);  // camera guide tables and caches, not timed
      const WorkCounters before = renderer.work();
      // The fastest of three 8-spp passes: the least disturbed by anything else on the machine.
      double seconds = 1e30;
      for (int repeat = 0; repeat < 3; ++repeat) {
        const auto t0 = std::chrono::steady_clock::now();
        renderer.renderPass(film, 8);
        seconds = std::min(seconds, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      WorkCounters w = renderer.work() - before;
      // Three passes counted, the fastest timed: one pass's work.
      Row row{{double(w.samples), double(w.collisions), double(w.segments), double(w.rays), double(w.knots), double(w.guided), double(w.guides)},
              seconds};
      for (double& x : row.x) x /= 3.0;
      rows.push_back(row);
      std::printf("%-18s %-13s %.3f s: samples %llu collisions %llu segments %llu rays %llu knots %llu guided %llu guides %llu\n", name, preset,
                  seconds, (unsigned long long)w.samples, (unsigned long long)w.collisions, (unsigned long long)w.segments,
                  (unsigned long long)w.rays, (unsigned long long)w.knots, (unsigned long long)w.guided, (unsigned long long)w.guides);
    }
  }
  // Relative least squares (each row weighted by 1 / its time), with terms whose coefficient comes
  // out negative dropped and the fit redone.
  bool active[kTerms];
  std::fill(active, active + kTerms, true);
  double c[kTerms] = {};
  for (int round = 0; round < 5; ++round) {
    double a[kTerms][kTerms + 1] = {};
    for (const Row& r : rows) {
      const double wgt = 1.0 / (r.seconds * r.seconds);
      for (int i = 0; i < kTerms; ++i) {
        if (!active[i]) continue;
        // The right-hand side whatever else is dropped (it was filled only with term 0 active, so
        // dropping the per-sample term zeroed the whole fit).
        a[i][kTerms] += r.x[i] * r.seconds * wgt;
        for (int j = 0; j < kTerms; ++j)
          if (active[j]) a[i][j] += r.x[i] * r.x[j] * wgt;
      }
    }
    for (int i = 0; i < kTerms; ++i)
      if (!active[i]) a[i][i] = 1.0, a[i][kTerms] = 0.0;
    for (int i = 0; i < kTerms; ++i) {  // Gauss-Jordan
      int pivot = i;
      for (int k = i + 1; k < kTerms; ++k)
        if (std::abs(a[k][i]) > std::abs(a[pivot][i])) pivot = k;
      for (int j = 0; j <= kTerms; ++j) std::swap(a[i][j], a[pivot][j]);
      for (int k = 0; k < kTerms; ++k) {
        if (k == i || a[i][i] == 0.0) continue;
        const double f = a[k][i] / a[i][i];
        for (int j = 0; j <= kTerms; ++j) a[k][j] -= f * a[i][j];
      }
    }
    bool dropped = false;
    for (int i = 0; i < kTerms; ++i) {
      c[i] = a[i][i] != 0.0 ? a[i][kTerms] / a[i][i] : 0.0;
      if (active[i] && c[i] < 0.0) active[i] = false, dropped = true;
    }
    if (!dropped) break;
  }
  // Relative errors of a model over the rows: the worst and the rms, after the one scale factor
  // that fits best (only the constants' ratios matter; the machine sets their scale).
  auto errors = [&](const double* coefficients, double& worst, double& rms) {
    std::vector<double> ratio;  // predicted / measured, per row
    double sxy = 0.0, sxx = 0.0;
    for (const Row& r : rows) {
      double predicted = 0.0;
      for (int i = 0; i < kTerms; ++i) predicted += coefficients[i] * r.x[i];
      ratio.push_back(predicted / r.seconds);
      sxy += ratio.back(), sxx += ratio.back() * ratio.back();
    }
    const double scale = sxx > 0.0 ? sxy / sxx : 1.0;  // least squares of scale x ratio against 1
    worst = rms = 0.0;
    for (double q : ratio) {
      const double e = scale * q - 1.0;
      worst = std::max(worst, std::abs(e)), rms += e * e;
    }
    rms = std::sqrt(rms / static_cast<double>(std::max<size_t>(1, ratio.size())));
  };
  double worst = 0.0, rms = 0.0;
  errors(c, worst, rms);
  std::printf("ns per operation: samples %.1f, collisions %.1f, segments %.1f, rays %.1f, knots %.1f, guided %.1f, guides %.1f (relative error rms %.0f%%, worst %.0f%%)\n",
              1e9 * c[0], 1e9 * c[1], 1e9 * c[2], 1e9 * c[3], 1e9 * c[4], 1e9 * c[5], 1e9 * c[6], 100.0 * rms, 100.0 * worst);
  // The constants the renderer ships (work.h), judged on the same rows: refit them when these
  // errors are well above the fit's.
  using C = WorkCost;
  const double shipped[kTerms] = {C::kSample, C::kCollision, C::kSegment, C::kRay, C::kKnot, C::kGuided, C::kGuide};
  errors(shipped, worst, rms);
  std::printf("work.h's constants on these rows: relative error rms %.0f%%, worst %.0f%%\n", 100.0 * rms, 100.0 * worst);
  return 0;
}

// A --sweep value as the chart's x: a number, or a switch's false / true as 0 / 1.
double sweepNumber(const std::string& v) {
  if (v == "false") return 0.0;
  if (v == "true") return 1.0;
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0') throw InputError("--sweep: expected numeric values (or true, false), got \"" + v + "\"");
  return x;
}

int bench(const std::string& scenePath, const std::string& strategiesText, const std::string& timesText, const std::string& refPath,
          int refSpp, const std::string& refStrategy, const std::vector<std::string>& refSets, const std::string& outDir, int threads,
          const std::vector<std::string>& sets, const std::string& sweep) {
  // --sweep KEY=V1,V2,...: every strategy is benched once per value (as --set KEY=V).
  std::string sweepKey;
  std::vector<std::string> sweepValues{""};
  if (!sweep.empty()) {
    const auto eq = sweep.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("--sweep: expected KEY=V1,V2,..., got \"" + sweep + "\"");
    sweepKey = sweep.substr(0, eq);
    sweepValues = splitList(sweep.substr(eq + 1));
    if (sweepValues.empty()) throw InputError("--sweep: expected at least one value after '='");
    for (const auto& v : sweepValues) sweepNumber(v);  // every value checked before any render
  }
  const auto strategies = splitList(strategiesText);
  std::vector<double> times;
  for (const auto& t : splitList(timesText)) {
    try {
      times.push_back(std::stod(t));
    } catch (...) {
      throw InputError("--times: expected comma-separated seconds, got \"" + timesText + "\"");
    }
    // At most render.time_s's bound: a budget of 1e30 s rendered until killed.
    if (!(times.back() > 0.0 && times.back() <= 1e7)) throw InputError("--times: expected positive seconds, at most 1e7, got " + t);
  }
  if (strategies.empty()) throw InputError("--strategies: expected at least one preset");
  if (times.empty()) throw InputError("--times: expected at least one time budget");
  std::sort(times.begin(), times.end());
  for (const auto& s : strategies) strategyPreset(s, "--strategies");
  std::filesystem::create_directories(outDir);

  Image reference;
  std::string referenceNote;
  if (!refPath.empty()) {
    reference = readExr(refPath);
    referenceNote = "reference: " + refPath;
  } else {
    // The benched runs' edits, then the reference's own (a strategy field, a seed): a reference of
    // far lower noise than any preset gives in the same time is one command, cached like the rest.
    std::vector<std::string> referenceSets = sets;
    referenceSets.insert(referenceSets.end(), refSets.begin(), refSets.end());
    // The --set edits checked alone first, so that an error from here on is a --reference-set's and
    // says so.
    loadSceneDesc(scenePath, sets, refStrategy);
    SceneDesc refDesc;
    try {
      refDesc = sceneWith(scenePath, refStrategy, referenceSets);
    } catch (const InputError& e) {
      std::string what = e.what();
      const std::string setLabel = "(--set ";
      if (const size_t at = what.find(setLabel); at != std::string::npos) what.replace(at, setLabel.size(), "(--reference-set ");
      else what = "--reference-set: " + what;
      throw InputError(what);
    }
    std::string cachePath;
    std::string edits;
    for (const auto& e : refSets) edits += ", --reference-set " + e;
    std::printf("reference: %s at %d spp%s (cached by scene hash)...\n", refStrategy.c_str(), refSpp, edits.c_str());
    std::fflush(stdout);
    const auto t0 = std::chrono::steady_clock::now();
    reference = cachedReference(refDesc, refDesc.strategy, refSpp, threads, &cachePath);
    std::printf("reference ready in %.1f s: %s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                cachePath.c_str());
    referenceNote = "reference: " + refStrategy + " at " + std::to_string(refSpp) + " spp" + edits + ", " + cachePath;
  }

  std::vector<ConvergencePoint> points;
  std::vector<SweepPoint> sweepPoints;
  for (const auto& value : sweepValues) {
    // Every strategy's scene (auto decides here), then each budget's renders side by side
    // (renderSideBySide): the clock's swings fall on all strategies alike.
    struct Contender {
      std::string label, strategy, note;
      std::shared_ptr<Scene> scene;
      double pilot = 0.0, pilotWork = 0.0;  // auto's decision (rules, probes, pilot), charged to its time
    };
    std::vector<Contender> contenders;
    for (const auto& strategy : strategies) {
      std::vector<std::string> runSets = sets;
      Contender c;
      c.label = c.strategy = strategy;
      if (!sweepKey.empty()) {
        runSets.push_back(sweepKey + "=" + value);
        c.label = strategy + " " + sweepKey.substr(sweepKey.rfind('.') + 1) + "=" + value;
      }
      SceneDesc desc = sceneWith(scenePath, strategy, runSets);
      c.scene = buildScene(desc);
      if (auto probes = c.scene->probes()) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%zu probes, %.2f s", probes->probes().size(), probes->learnSeconds());
        c.note = buf;
      }
      if (reference.width != c.scene->camera().width() || reference.height != c.scene->camera().height())
        throw InputError(refPath + ": reference is " + std::to_string(reference.width) + "x" + std::to_string(reference.height) +
                         ", expected the scene's " + std::to_string(c.scene->camera().width()) + "x" + std::to_string(c.scene->camera().height()));
      if (const AutoDecision* d = c.scene->autoDecision()) c.pilot = d->chargedSeconds(), c.pilotWork = d->pilotWork;
      contenders.push_back(std::move(c));
    }
    for (double budget : times) {
      std::vector<std::unique_ptr<ProgressiveRenderer>> renderers;
      std::vector<EqualTimeRun> sideBySide;
      for (const Contender& c : contenders) {
        renderers.push_back(std::make_unique<ProgressiveRenderer>(c.scene, RenderOptions{threads, 32}));
        // auto renders for what is left of the budget, from its pilot's samples where it kept them.
        sideBySide.push_back({renderers.back().get(), continueFromPilot(*c.scene, 0), c.pilot});
      }
      renderSideBySide(sideBySide, budget);
      for (size_t i = 0; i < contenders.size(); ++i) {
        const Contender& c = contenders[i];
        const Film& film = sideBySide[i].film;
        ConvergencePoint p;
        p.strategy = c.label;
        p.budgetSeconds = budget;
        p.seconds = sideBySide[i].seconds;
        p.spp = film.spp();
        p.work = c.pilotWork + renderers[i]->work().cost();
        p.rejected = film.rejectedSamples();
        const ErrorMetrics e = film.spp() > 0 ? imageError(film.meanImage(), reference.rgb) : ErrorMetrics{NAN, NAN};
        p.mse = e.mse;
        p.relmse = e.relmse;
        points.push_back(p);
        std::printf("%-14s budget %7.2f s  time %7.2f s  spp %6d  mse %.4g  relmse %.4g\n", c.label.c_str(), budget, p.seconds, p.spp,
                    p.mse, p.relmse);
        if (const SplitMap* split = renderers[i]->adaptiveSplit()) std::printf("  %s\n", split->summary().c_str());
        if (budget == times.back() && !sweepKey.empty())
          sweepPoints.push_back({c.strategy, sweepNumber(value), 1.0 / (p.relmse * p.seconds), c.note});
      }
      std::fflush(stdout);
    }
  }
  const std::string csv = (std::filesystem::path(outDir) / "convergence.csv").string();
  const std::string svg = (std::filesystem::path(outDir) / "convergence.svg").string();
  std::ostringstream comment;
  comment << "scene: " << scenePath << "; threads: " << (threads > 0 ? std::to_string(threads) : "all") << "; " << referenceNote;
  writeConvergenceCsv(csv, points, comment.str());
  writeConvergenceSvg(svg, points, std::filesystem::path(scenePath).stem().string() + ": error versus time");
  if (!sweepKey.empty()) {
    const std::string sweepCsv = (std::filesystem::path(outDir) / "sweep.csv").string();
    const std::string sweepSvg = (std::filesystem::path(outDir) / "sweep.svg").string();
    std::ostringstream out;
    out << "# efficiency = 1 / (relmse x time_s) at the largest budget; " << kRelMseFormula << "\n";
    out << "strategy," << sweepKey << ",efficiency,note\n";
    for (const auto& p : sweepPoints) out << p.strategy << ',' << p.value << ',' << p.efficiency << ",\"" << p.note << "\"\n";
    writeTextAtomically(sweepCsv, out.str());
    writeSweepSvg(sweepSvg, sweepPoints, std::filesystem::path(scenePath).stem().string() + ": efficiency versus " + sweepKey, sweepKey);
    std::printf("wrote %s and %s\n", sweepCsv.c_str(), sweepSvg.c_str());
  }
  // relMSE weighs every pixel's relative error (dark pixels count as much as bright ones); the
  // absolute MSE's efficiency is printed beside it because the two can rank strategies differently.
  std::printf("\nefficiency = 1 / (relMSE x time) at the largest budget (%.2f s); absolute: 1 / (MSE x time):\n", times.back());
  double base = 0.0, baseAbsolute = 0.0, baseWork = 0.0, baseWorkAbsolute = 0.0;
  std::string baseLabel;
  for (const auto& p : points) {
    if (p.budgetSeconds != times.back()) continue;
    const double eff = 1.0 / (p.relmse * p.seconds), absolute = 1.0 / (p.mse * p.seconds);
    if (base == 0.0) base = eff, baseAbsolute = absolute, baseLabel = p.strategy;
    std::printf("  %-28s %10.4g   (x%.2f vs %s)   absolute %10.4g (x%.2f)\n", p.strategy.c_str(), eff, eff / base, baseLabel.c_str(), absolute,
                absolute / baseAbsolute);
  }
  // The same ratios with counted work for time: the clock varies 15-30% between runs of one command
  // on a shared machine, the work counts do not (the work model's fit to time is within about 20%).
  std::printf("by counted work instead of time (work.h; no clock), 1 / (relMSE x work) / 1 / (MSE x work):\n");
  for (const auto& p : points) {
    if (p.budgetSeconds != times.back()) continue;
    const double eff = 1.0 / (p.relmse * p.work), absolute = 1.0 / (p.mse * p.work);
    if (baseWork == 0.0) baseWork = eff, baseWorkAbsolute = absolute;
    std::printf("  %-28s x%.2f / x%.2f vs %s   (%.3g work per sample per pixel)\n", p.strategy.c_str(), eff / baseWork, absolute / baseWorkAbsolute,
                baseLabel.c_str(), p.work / std::max(1.0, static_cast<double>(p.spp) * reference.width * reference.height));
  }
  std::printf("wrote %s and %s\n", csv.c_str(), svg.c_str());
  return 0;
}

// The guide inspector along one pixel's camera ray (or a secondary ray of a path chosen by seed):
// the ideal, guided, tracked and MIS densities as CSV and SVG, and each one's variance factor.
int inspect(const std::string& scenePath, const std::vector<int>& pixel, int secondarySeed, int lightSamples, const std::string& preset,
            const std::vector<std::string>& sets, const std::string& outDir) {
  const SceneDesc desc = sceneWith(scenePath, preset, sets);
  if (pixel[0] >= desc.camera.resolution.first || pixel[1] >= desc.camera.resolution.second)
    throw InputError("--pixel: expected a pixel inside the " + std::to_string(desc.camera.resolution.first) + "x" +
                     std::to_string(desc.camera.resolution.second) + " image, got " + std::to_string(pixel[0]) + "," + std::to_string(pixel[1]));
  auto scene = buildScene(desc);
  GuideInspectOptions options;
  options.secondary_seed = secondarySeed;
  options.light_samples = lightSamples;
  const auto t0 = std::chrono::steady_clock::now();
  const GuideInspection r = inspectGuide(*scene, pixel[0], pixel[1], options);
  std::filesystem::create_directories(outDir);
  const std::string stem = std::filesystem::path(scenePath).stem().string() + "-" + std::to_string(pixel[0]) + "-" + std::to_string(pixel[1]) +
                           (secondarySeed >= 0 ? "-secondary" + std::to_string(secondarySeed) : "");
  const std::string csv = (std::filesystem::path(outDir) / (stem + ".csv")).string();
  const std::string svg = (std::filesystem::path(outDir) / (stem + ".svg")).string();
  writeInspectionCsv(csv, r);
  writeInspectionSvg(svg, r, stem + " (" + desc.strategy.preset + "): distance densities along the " + (r.segment ? "secondary" : "camera") + " ray");
  std::printf("%s\n(%.2f s)\nwrote %s and %s\n", inspectionSummary(r).c_str(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), csv.c_str(), svg.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Candela: progressive CPU path tracer for heterogeneous volumes (batch tools)"};
  app.require_subcommand(1);

  std::string scenePath, out, preset, refPath, strategies, times, refStrategy = "conventional";
  std::string upAxis = "auto", framesText;
  VdbImportOptions importOptions;
  std::vector<std::string> sets;
  int spp = 0, seed = -1, threads = 0, refSpp = 1024;
  double seconds = 0.0;

  const CLI::Validator finitePositive = candela::finitePositive();
  double maxMemoryGb = 0.0;
  app.add_option("--max-memory", maxMemoryGb,
                 "Memory budget in GB for any one input-sized structure (film, grid, probes); default 4 or CANDELA_MAX_MEMORY_GB")
      ->check(finitePositive);
  app.fallthrough();

  auto* r = app.add_subcommand("render", "Render a scene to an EXR (scene-linear) or PNG (sRGB) image");
  r->add_option("scene", scenePath, "Scene JSON file, or a .vdb to open as a volume (grids recognised by name, framed, lit by a sun and sky)")
      ->required()
      ->check(CLI::ExistingFile);
  r->add_option("--up", upAxis, "For a .vdb: its up axis, auto (Z when Blender wrote it), y or z")->check(CLI::IsMember({"auto", "y", "z"}));
  r->add_flag("!--no-light-rig", importOptions.light_rig, "For a .vdb: no default sun and sky");
  r->add_flag("!--no-ground", importOptions.ground, "For a .vdb: no ground plane under the volume");
  r->add_option("--frames", framesText, "Render frames A-B of a sequence (volume files with fire.####.vdb patterns); OUT gets .#### unless it has a pattern");
  r->add_option("-o,--output", out, "Output image (.exr or .png)")->required();
  auto* sppOpt = r->add_option("--spp", spp, "Samples per pixel")->check(CLI::Range(1, 1 << 24));
  r->add_option("--time", seconds, "Render for this many seconds instead")->check(finitePositive)->excludes(sppOpt);
  r->add_option("--seed", seed, "Random seed")->check(CLI::NonNegativeNumber);
  r->add_option("--threads", threads, "Worker threads (0: all)")->check(CLI::NonNegativeNumber);
  r->add_option("--strategy", preset, "Strategy preset: " + [] {
    std::string s;
    for (const auto& n : strategyPresetNames()) s += (s.empty() ? "" : ", ") + n;
    return s;
  }());
  r->add_option("--set", sets, "Edit any scene or strategy parameter by JSON path, e.g. volumes.0.g=0.5");

  auto* b = app.add_subcommand("bench", "Equal-time convergence of strategies against a reference");
  b->add_option("scene", scenePath, "Scene JSON file")->required()->check(CLI::ExistingFile);
  b->add_option("--strategies", strategies, "Comma-separated strategy presets")->required();
  b->add_option("--times", times, "Comma-separated time budgets in seconds")->required();
  auto* refOpt = b->add_option("--reference", refPath, "Reference EXR")->check(CLI::ExistingFile);
  b->add_option("--reference-spp", refSpp, "Render (or reuse the cached) reference at this spp")->excludes(refOpt)->check(CLI::PositiveNumber);
  b->add_option("--reference-strategy", refStrategy, "Strategy preset of the rendered reference")->excludes(refOpt);
  std::vector<std::string> refSets;
  b->add_option("--reference-set", refSets, "Edit a parameter of the rendered reference only (after --set), e.g. strategy.guiding.combination=balance")
      ->excludes(refOpt);
  b->add_option("-o,--output", out, "Output directory")->required();
  b->add_option("--threads", threads, "Worker threads (0: all)")->check(CLI::NonNegativeNumber);
  b->add_option("--set", sets, "Edit any scene or strategy parameter by JSON path");
  std::string sweep;
  b->add_option("--sweep", sweep, "KEY=V1,V2,...: bench every strategy once per value; writes sweep.csv and sweep.svg (efficiency vs value)");

  std::string genType;
  GeneratorDesc gen;
  std::vector<float> size;
  auto* g = app.add_subcommand("generate", "Write a built-in procedural volume to a .vdb file");
  g->add_option("type", genType, "constant, ramp, torch, mist, cloud or plume")->required();
  g->add_option("-o,--output", out, "Output .vdb")->required();
  g->add_option("--seed", gen.seed, "Noise seed");
  g->add_option("--resolution", gen.resolution, "Voxels along the longest axis")->check(CLI::Range(2, 1024));
  g->add_option("--size", size, "World extent X,Y,Z")->delimiter(',')->expected(3);
  auto* generateValue = g->add_option("--value", gen.value,
                                      "Density: constant/ramp's; for torch, mist, cloud and plume their peak (default: what the shipped "
                                      "scenes give the shape, cloud 12, torch 6, plume 1.5, mist 0.1)");
  g->add_option("--temperature", gen.temperature, "constant/ramp temperature");

  bool quick = false;
  auto* cal = app.add_subcommand("calibrate", "Fit the work-cost constants the auto strategy's pilot uses (work.h) against render time");
  auto* rep = app.add_subcommand("report", "Speed-versus-accuracy report: every scene x strategy at equal time, plus the stability suite (DIR/index.html)");
  rep->add_flag("--quick", quick, "Lower resolution and budgets (CI: under 5 minutes on 2 cores)");
  rep->add_option("-o,--output", out, "Output directory")->required();
  rep->add_option("--threads", threads, "Worker threads (0: all)")->check(CLI::NonNegativeNumber);
  int reportSeeds = 0;
  rep->add_option("--seeds", reportSeeds,
                  "Seeds (17, 18, ...) every strategy renders at the largest budget on every scene; auto's ratios are their median (default " +
                      std::to_string(kReportSeeds) + ", " + std::to_string(kWideSpreadReportSeeds) + " on the scenes whose seeds disagree most, " +
                      std::to_string(kQuickReportSeeds) + " with --quick)")
      ->check(CLI::Range(1, 64));
  std::vector<std::string> reportScenes;
  rep->add_option("--scenes", reportScenes, "Only these report scenes, comma-separated (" + reportSceneList() + "; default all)")->delimiter(',');
  bool noStability = false;
  rep->add_flag("--no-stability", noStability, "Skip the stability suite");

  std::vector<int> pixel;
  int secondarySeed = -1, lightSamples = 256;
  auto* ins = app.add_subcommand("inspect", "Guide inspector: distance densities along a pixel's ray (ideal, guided, tracked, MIS) with variance factors");
  ins->add_option("scene", scenePath, "Scene JSON file")->required()->check(CLI::ExistingFile);
  ins->add_option("--pixel", pixel, "X,Y of the pixel (0,0 top left)")->delimiter(',')->expected(2)->required()->check(CLI::NonNegativeNumber);
  ins->add_option("--secondary", secondarySeed, "Inspect the secondary ray of the path chosen by this seed instead")->check(CLI::NonNegativeNumber);
  ins->add_option("--light-samples", lightSamples, "Light samples per point for the ideal curve")->check(CLI::Range(1, 1 << 20));
  ins->add_option("--strategy", preset, "Strategy preset");
  ins->add_option("--set", sets, "Edit any scene or strategy parameter by JSON path");
  ins->add_option("-o,--output", out, "Output directory")->required();

  CLI11_PARSE(app, argc, argv);
  try {
    checkMemoryBudgetEnvironment();
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (maxMemoryGb > 0.0) setMemoryBudgetBytes(static_cast<size_t>(std::min(maxMemoryGb, 1e6) * 1073741824.0));
  try {
    if (rep->parsed()) return runReport(quick, out, threads, reportSeeds, reportScenes, !noStability);
    if (cal->parsed()) return calibrate();
    if (r->parsed()) {
      importOptions.up = upAxis == "z" ? UpAxis::Z : upAxis == "y" ? UpAxis::Y : UpAxis::Auto;
      return render(scenePath, out, spp, seconds, seed, threads, preset, sets, importOptions, framesText);
    }
    if (b->parsed()) return bench(scenePath, strategies, times, refPath, refSpp, refStrategy, refSets, out, threads, sets, sweep);
    if (ins->parsed()) return inspect(scenePath, pixel, secondarySeed, lightSamples, preset, sets, out);
    if (g->parsed()) {
      gen.type = genType;
      if (generateValue->count() == 0) gen.value = standaloneDensity(genType);
      if (size.size() == 3) gen.size = Vec3(size[0], size[1], size[2]);
      VolumeDesc check;
      check.has_generator = true;
      check.generator = gen;
      Json j = toJson(gen);
      GeneratorDesc validated;
      fromJson(j, validated, "generate", "generator");
      const auto t0 = std::chrono::steady_clock::now();
      if (std::filesystem::path(out).has_parent_path()) std::filesystem::create_directories(std::filesystem::path(out).parent_path());
      writeGeneratedVolume(validated, out);
      std::printf("wrote %s (%s) in %.2f s\n", out.c_str(), genType.c_str(),
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      return 0;
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "error: %s: out of memory (lower the resolution or grid sizes, or see --max-memory)\n",
                 scenePath.empty() ? out.c_str() : scenePath.c_str());
    return 1;
  } catch (const std::exception& e) {
    // Never a bare library message: name the input it came from.
    std::fprintf(stderr, "error: %s: %s\n", scenePath.empty() ? out.c_str() : scenePath.c_str(), e.what());
    return 1;
  }
  return 0;
}
