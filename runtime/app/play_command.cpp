// `kaskad play` itself: which files a shard runs, merging shard summaries, and the command
// (files and folders, --merge, --jobs as one process per shard).
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>

#include <nlohmann/json.hpp>

#include "runtime/app/playback.h"
#include "runtime/core/atomic_file.h"
#include "runtime/core/json_reader.h"

extern char** environ;

namespace kaskad {

namespace fs = std::filesystem;
using json = nlohmann::json;
using json_reader::parse_json_file;

std::vector<std::size_t> shard_files(std::size_t count, int index, int n) {
  std::vector<std::size_t> out;
  for (std::size_t i = std::size_t(index); n > 0 && i < count; i += std::size_t(n)) out.push_back(i);
  return out;
}

Result<std::size_t> merge_summaries(const std::vector<fs::path>& dirs, const fs::path& out_dir) {
  json merged = {{"kaskad_play_summary", 1}, {"merged_from", json::array()}, {"files", json::array()}};
  std::size_t failed = 0, files = 0;
  for (const fs::path& dir : dirs) {
    const fs::path file = dir / "summary.json";
    auto doc = parse_json_file(file);
    if (!doc) {
      Error e = doc.error();
      e.message += " (is this a kaskad play --out folder?)";
      return e;
    }
    if (!doc->is_object() || !doc->contains("files") || !(*doc)["files"].is_array())
      return Error{file.string(), "/files", "not a kaskad play summary"};
    merged["merged_from"].push_back(file.string());
    for (const json& f : (*doc)["files"]) {
      if (!f.is_object() || !f.contains("ok") || !f["ok"].is_boolean() || !f.contains("file"))
        return Error{file.string(), "/files", "an entry lacks file or ok"};
      ++files;
      if (!f["ok"].get<bool>()) {
        ++failed;
        std::printf("FAILED    %s\n", f["file"].dump().c_str());
        if (f.contains("failures") && f["failures"].is_array())
          for (const json& x : f["failures"]) std::printf("  %s\n", x.dump().c_str());
      }
      merged["files"].push_back(f);
    }
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  const fs::path path = out_dir / "summary.json";
  KASKAD_TRY(write_file_atomic(path, merged.dump(2) + "\n"));
  std::printf("merged    %zu summaries, %zu files, %zu failed -> %s\n", dirs.size(), files, failed,
              path.string().c_str());
  return failed;
}

int run_play(const PlayCommandOptions& command) {
  auto usage = [](const std::string& msg) {
    std::fprintf(stderr, "kaskad play: %s\n(run `kaskad play --help` for usage)\n", msg.c_str());
    return 2;
  };
  const PlayOptions& options = command.run;
  const std::vector<fs::path>& inputs = command.inputs;
  const bool out_given = command.out_given;
  const bool merge = command.merge;
  const int jobs = command.jobs;
  // Like every output folder Kaskad makes: one level, in a folder that exists (the default
  // out/play is made whole).
  if (out_given) {
    if (Status st = check_output_folder_to_make(options.out_dir); !st) {
      std::fprintf(stderr, "kaskad: error: --out: %s\n", st.error().to_string().c_str());
      return 1;
    }
  }
  if (merge) {
    if (inputs.empty()) return usage("--merge needs the output folders of the shards");
    auto failed = merge_summaries(inputs, options.out_dir);
    if (!failed) {
      std::fprintf(stderr, "kaskad: error: %s\n", failed.error().to_string().c_str());
      return 1;
    }
    return *failed == 0 ? 0 : 1;
  }
  // A folder stands for its *.json files.
  std::vector<fs::path> files;
  for (const fs::path& in : inputs) {
    std::error_code ec;
    if (fs::is_directory(in, ec)) {
      for (const auto& entry : fs::directory_iterator(in, ec))
        if (entry.path().extension() == ".json") files.push_back(entry.path());
    } else {
      files.push_back(in);
    }
  }
  if (files.empty()) return usage("name playback files or folders of them");
  if (jobs > 1) {
    if (options.shard_count > 1) return usage("give --jobs or --shard, not both");
    // One process per shard (one GL context each), then one merged summary.
    std::error_code ec;
    fs::create_directories(options.out_dir, ec);
    if (ec) {
      std::fprintf(stderr, "kaskad: error: %s: cannot create the output folder: %s\n",
                   options.out_dir.string().c_str(), ec.message().c_str());
      return 1;
    }
    std::vector<pid_t> children;
    std::vector<fs::path> dirs;
    for (int j = 0; j < jobs; ++j) {
      dirs.push_back(options.out_dir / ("shard-" + std::to_string(j)));
      std::vector<std::string> args = {"kaskad", "play", "--shard",
                                       std::to_string(j) + "/" + std::to_string(jobs), "--out",
                                       dirs.back().string(), options.headless ? "--headless" : "--window"};
      if (options.update_goldens) args.push_back("--update-goldens");
      for (const fs::path& f : files) args.push_back(f.string());
      std::vector<char*> cargs;
      for (std::string& a : args) cargs.push_back(a.data());
      cargs.push_back(nullptr);
      pid_t pid = 0;
      if (posix_spawn(&pid, "/proc/self/exe", nullptr, nullptr, cargs.data(), environ) != 0) {
        std::fprintf(stderr, "kaskad: error: cannot start a play process for shard %d\n", j);
        return 1;
      }
      children.push_back(pid);
    }
    bool crashed = false;
    for (std::size_t j = 0; j < children.size(); ++j) {
      int status = 0;
      waitpid(children[j], &status, 0);
      // 0 and 1 are results with a summary; anything else (a signal, a usage error), or no
      // summary, is a broken run.
      std::error_code ec;
      const bool summary = fs::exists(dirs[j] / "summary.json", ec);
      if (WIFEXITED(status) && WEXITSTATUS(status) <= 1 && summary) continue;
      crashed = true;
      const std::string how = WIFSIGNALED(status)
                                  ? "was killed by signal " + std::to_string(WTERMSIG(status))
                                  : "exited with status " + std::to_string(WEXITSTATUS(status));
      std::fprintf(stderr, "kaskad: error: the process of shard %zu/%d %s\n", j, jobs, how.c_str());
      // A shard that left no summary is recorded as failed, so the merge still reports the rest.
      if (!summary) {
        fs::create_directory(dirs[j], ec);
        const std::string message = "the shard process " + how + " before writing its summary";
        const json stub = {
            {"kaskad_play_summary", 1},
            {"shard", std::to_string(j) + "/" + std::to_string(jobs)},
            {"files",
             json::array({{{"file", dirs[j].string()},
                           {"ok", false},
                           {"failures", json::array({{{"frame", -1}, {"message", message}}})}}})}};
        if (auto st = write_file_atomic(dirs[j] / "summary.json", stub.dump(2) + "\n"); !st)
          std::fprintf(stderr, "kaskad: error: %s\n", st.error().to_string().c_str());
      }
    }
    auto failed = merge_summaries(dirs, options.out_dir);
    if (!failed) {
      std::fprintf(stderr, "kaskad: error: %s\n", failed.error().to_string().c_str());
      return 1;
    }
    return crashed || *failed != 0 ? 1 : 0;
  }
  auto failures = run_playbacks(files, options);
  if (!failures) {
    std::fprintf(stderr, "kaskad: error: %s\n", failures.error().to_string().c_str());
    return 1;
  }
  std::printf("summary   %s: %zu failed expectation(s)\n",
              (options.out_dir / "summary.json").string().c_str(), failures->size());
  return failures->empty() ? 0 : 1;
}

}  // namespace kaskad
