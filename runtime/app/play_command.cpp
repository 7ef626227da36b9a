// `kaskad play` itself: which files a shard runs, merging shard summaries, and the command
// (files and folders, --merge, --jobs as one process per shard).
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <set>

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

namespace {

using json_reader::ContentError;
using json_reader::ObjectReader;
using json_reader::type_name;

// The entries of one shard's summary.json (as run_playbacks writes it, change together), each
// checked: errors name the file and the JSON pointer ("/files/3/ok: expected true or false").
Result<json> read_summary(const fs::path& file) {
  auto doc = parse_json_file(file);
  if (!doc) {
    Error e = doc.error();
    e.message += " (is this a kaskad play --out folder?)";
    return e;
  }
  try {
    ObjectReader r(*doc, "");
    if (!r.has("kaskad_play_summary") || !r.has("files"))
      return Error{file.string(), "", "not a kaskad play summary (no kaskad_play_summary and files)"};
    int version = 0;
    r.integer("kaskad_play_summary", version, 1, 1000000);
    if (version != 1)
      json_reader::fail(r.at("kaskad_play_summary"),
                        "version " + std::to_string(version) + " is newer than this build reads (1)");
    if (r.has("shard")) {
      std::string shard;
      r.string("shard", shard);
      // "i/n" with 0 <= i < n, as --shard takes it.
      const auto slash = shard.find('/');
      const std::string i = shard.substr(0, slash), n = slash == std::string::npos ? "" : shard.substr(slash + 1);
      const auto digits = [](const std::string& s) {
        return !s.empty() && s.size() <= 6 && s.find_first_not_of("0123456789") == std::string::npos;
      };
      if (!digits(i) || !digits(n) || std::stol(i) >= std::stol(n))
        json_reader::fail(r.at("shard"), "'" + shard + "' is not a shard i/n with 0 <= i < n");
    }
    if (r.has("merged_from")) {
      const json& from = r.raw("merged_from");
      if (!from.is_array()) json_reader::fail(r.at("merged_from"), "expected an array, got " + type_name(from));
      for (std::size_t i = 0; i < from.size(); ++i)
        if (!from[i].is_string())
          json_reader::fail(r.at("merged_from") + "/" + std::to_string(i),
                            "expected a string, got " + type_name(from[i]));
    }
    const json& files = r.raw("files");
    if (!files.is_array()) json_reader::fail(r.at("files"), "expected an array, got " + type_name(files));
    r.finish();
    for (std::size_t i = 0; i < files.size(); ++i) {
      const std::string at = "/files/" + std::to_string(i);
      ObjectReader e(files[i], at);
      std::string name;
      if (!e.has("file")) json_reader::fail(at, "no 'file'");
      e.string("file", name);
      if (name.empty()) json_reader::fail(e.at("file"), "empty");
      if (!e.has("ok")) json_reader::fail(at, "no 'ok'");
      bool ok = false;
      e.boolean("ok", ok);
      int count = 0;
      e.integer("frames", count, 0, 100000);
      e.integer("captured", count, 0, 100000);
      float wall_s = 0.0f;
      e.number("wall_s", wall_s, 0.0f, 1e9f);
      std::size_t failures = 0;
      if (e.has("failures")) {
        const json& list = e.raw("failures");
        if (!list.is_array()) json_reader::fail(e.at("failures"), "expected an array, got " + type_name(list));
        for (std::size_t k = 0; k < list.size(); ++k) {
          ObjectReader f(list[k], e.at("failures") + "/" + std::to_string(k));
          int frame = 0;
          std::string message;
          f.integer("frame", frame, -1, 100000);
          f.string("message", message);
          f.finish();
        }
        failures = list.size();
      }
      e.finish();
      if (ok && failures > 0)
        json_reader::fail(e.at("ok"), "true, but the entry lists " + std::to_string(failures) + " failure(s)");
    }
    return files;
  } catch (const ContentError& e) {
    return Error{file.string(), e.where, e.message};
  }
}

}  // namespace

Result<std::size_t> merge_summaries(const std::vector<fs::path>& dirs, const fs::path& out_dir) {
  // Every summary is read and checked before the merged one is written.
  json merged = {{"kaskad_play_summary", 1}, {"merged_from", json::array()}, {"files", json::array()}};
  std::size_t failed = 0, files = 0;
  std::vector<json> entries;
  for (const fs::path& dir : dirs) {
    const fs::path file = dir / "summary.json";
    auto read = read_summary(file);
    if (!read) return read.error();
    merged["merged_from"].push_back(file.string());
    entries.push_back(std::move(read.value()));
  }
  for (const json& list : entries)
    for (const json& f : list) {
      ++files;
      if (!f["ok"].get<bool>()) {
        ++failed;
        std::printf("FAILED    %s\n", f["file"].dump().c_str());
        if (f.contains("failures"))
          for (const json& x : f["failures"]) std::printf("  %s\n", x.dump().c_str());
      }
      merged["files"].push_back(f);
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
    std::set<std::string> seen;
    for (const fs::path& dir : inputs) {
      std::error_code ec;
      const fs::path same = fs::weakly_canonical(dir, ec);
      if (!seen.insert((ec ? dir : same).string()).second)
        return usage("--merge: the shard folder " + dir.string() + " is named twice");
    }
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
