// Output plumbing: CSV text, folders that appear whole or not at all, manifests.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <array>
#include <atomic>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/manifest.h"
#include "polrig/io/measured.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/plot.h"
#include "polrig/io/sweep_h5.h"
#include "polrig/suggest.h"
#include "support.h"

namespace polrig {
namespace {
namespace fs = std::filesystem;
using test::read_file;

fs::path fresh_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("polrig-test-io-" + name);
  fs::remove_all(p);
  return p;
}

TEST(Csv, WritesShortestExactNumbers) {
  CsvTable t({"a", "b", "c"});
  t.add_row({1.0, 0.1, 1.0 / 3.0});
  t.add_row({-2.5e-7, 360.0, 0.30000000000000004});
  EXPECT_EQ(t.text(), "a,b,c\n1,0.1,0.3333333333333333\n-2.5e-07,360,0.30000000000000004\n");
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_THROW(t.add_row({1.0}), std::logic_error);
}

// The writers' last guard: no NaN or infinity leaves in a CSV, except NaN in a column declared
// to mean "not defined"; the message names the column, the row and the value.
TEST(Csv, RefusesNonFiniteValuesNamingTheColumnAndRow) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CsvTable t({"pair", "bsd_mV", "ratio_pct"});
  t.add_row({1, 0.5, 2});
  for (double bad : {inf, -inf, nan}) {
    try {
      t.add_row({2, bad, 1});
      FAIL() << "accepted " << bad;
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("column 'bsd_mV' of row 2 (pair = 2) is "), std::string::npos) << msg;
      EXPECT_NE(msg.find(std::isnan(bad) ? "is nan" : bad > 0 ? "is inf" : "is -inf"), std::string::npos) << msg;
    }
  }
  EXPECT_EQ(t.rows(), 1u);  // a refused row is not kept
  EXPECT_THROW(t.add_row({2, 1, nan}), std::runtime_error);
  t.allow_undefined("ratio_pct");
  t.add_row({2, 1, nan});
  EXPECT_THROW(t.add_row({3, 1, inf}), std::runtime_error);  // undefined is NaN, never infinity
  EXPECT_EQ(t.text(), "pair,bsd_mV,ratio_pct\n1,0.5,2\n2,1,nan\n");
}

TEST(Suggest, EditDistanceIsTheTextbooks) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);  // Levenshtein's classic
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("simualte", "simulate"), 1u);  // one swap of neighbours
  EXPECT_EQ(edit_distance("ca", "abc"), 3u);             // optimal string alignment, not Damerau's 2
  EXPECT_EQ(nearest_name("L_SI", {"L_IS", "L_S", "alpha_S"}), std::optional<std::string>("L_IS"));
  EXPECT_EQ(nearest_name("frobnicate", {"simulate", "sweep"}), std::nullopt);
  EXPECT_EQ(did_you_mean("swep", {"sweep", "study"}), " (did you mean 'sweep'?)");
}

// Plots name CSV columns by header, so a writer's new column cannot shift what a plot shows.
TEST(PlotColumns, NamesBecomeGnuplotColumnLookups) {
  const std::vector<std::string> header{"theta_R_deg", "t_s", "V1_ideal", "method", "eccentricity.L_IS"};
  EXPECT_EQ(resolve_columns("$theta_R_deg:($V1_ideal*1e3)", header, "stops.csv"),
            "\"theta_R_deg\":(column(\"V1_ideal\")*1e3)");
  EXPECT_EQ(resolve_columns("$0:(@method eq 'cs' ? $t_s : NaN)", header, "x.csv"),
            "$0:(strcol(\"method\") eq 'cs' ? column(\"t_s\") : NaN)");
  EXPECT_EQ(resolve_columns("$eccentricity.L_IS:xtic(@method)", header, "x.csv"),
            "\"eccentricity.L_IS\":xtic(strcol(\"method\"))");
}

TEST(PlotColumns, AnUnknownNameOrAColumnNumberIsRefused) {
  const std::vector<std::string> header{"theta_R_deg", "V1"};
  EXPECT_THROW(resolve_columns("$theta_R_deg:$V2", header, "stops.csv"), std::logic_error);
  EXPECT_THROW(resolve_columns("2:($V1*1e3)", header, "stops.csv"), std::logic_error);
  EXPECT_THROW(resolve_columns("$theta_R_deg:($11*1e3)", header, "stops.csv"), std::logic_error);
  try {
    resolve_columns("$theta_R_deg:$V2", header, "stops.csv");
  } catch (const std::logic_error& e) {
    EXPECT_HAS(std::string(e.what()), "stops.csv");
    EXPECT_HAS(std::string(e.what()), "'V2'");
  }
}

TEST(OutputDir, AppearsOnlyOnCommit) {
  const fs::path base = fresh_dir("commit");
  const fs::path dest = base / "nested" / "out";
  {
    OutputDir out(dest, false);
    write_text_file(out.staging() / "x.csv", "x\n1\n");
    EXPECT_FALSE(fs::exists(dest));
    out.commit();
  }
  EXPECT_EQ(read_file(dest / "x.csv"), "x\n1\n");
  for (const auto& e : fs::directory_iterator(dest.parent_path()))
    EXPECT_EQ(e.path().filename(), "out");  // no staging folder left beside it
  fs::remove_all(base);
}

TEST(OutputDir, LeavesNothingWhenAbandoned) {
  const fs::path base = fresh_dir("abandon");
  const fs::path dest = base / "a" / "b" / "out";
  try {
    OutputDir out(dest, false);
    write_text_file(out.staging() / "half.csv", "x\n");
    throw std::runtime_error("simulated failure mid-way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(dest));
  EXPECT_FALSE(fs::exists(base / "a"));  // parents it created are removed again
  fs::remove_all(base);
}

TEST(OutputDir, AResumableFolderIsLockedKeptAndContinued) {
  const fs::path base = fresh_dir("resumable");
  const fs::path dest = base / "out", staging = base / ".out.resumable";
  const Resumable fresh{"record", false, false}, resume{"record", true, false}, restart{"record", false, true};
  {
    OutputDir out(dest, false, fresh);
    EXPECT_EQ(out.staging(), staging);
    EXPECT_FALSE(out.resuming());
    // Another writer of the same folder is refused, and does not remove this one's staging.
    try {
      OutputDir other(dest, false, fresh);
      ADD_FAILURE() << "a locked staging folder was opened twice";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("another polrig is writing this output folder now"), std::string::npos) << e.what();
    }
    write_text_file(out.staging() / "record", "1\n");
    out.keep_on_failure();
  }  // not committed: kept
  ASSERT_TRUE(fs::exists(staging / "record"));
  try {
    OutputDir again(dest, false, fresh);
    ADD_FAILURE() << "an interrupted run was started over without --force";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("--resume continues it; --force starts over"), std::string::npos) << e.what();
  }
  ASSERT_TRUE(fs::exists(staging / "record"));
  {
    OutputDir out(dest, false, resume);
    EXPECT_TRUE(out.resuming());
    EXPECT_EQ(read_file(out.staging() / "record"), "1\n");
    fs::remove(out.staging() / "record");
    out.commit();
  }
  EXPECT_TRUE(fs::exists(dest));
  EXPECT_FALSE(fs::exists(staging));
  // Without a record (killed before its first), a staging folder is started over; --force
  // empties one with a record; an error before keep_on_failure() removes it.
  fs::create_directory(staging);
  write_text_file(staging / "junk", "x");
  try {
    OutputDir out(base / "out", false, fresh);
    ADD_FAILURE() << "the destination exists";
  } catch (const std::runtime_error&) {
  }
  {
    OutputDir out(dest, true, restart);
    EXPECT_FALSE(fs::exists(staging / "junk"));
  }
  EXPECT_FALSE(fs::exists(staging));
  fs::remove_all(dest);
  fs::create_directory(staging);
  write_text_file(staging / "junk", "x");
  {
    OutputDir out(dest, false, fresh);
    EXPECT_FALSE(out.resuming());
    EXPECT_FALSE(fs::exists(staging / "junk"));
  }
  EXPECT_FALSE(fs::exists(staging));
  fs::remove_all(base);
}

TEST(SweepH5, TheBytesDependOnlyOnTheValuesNotOnTheBlocks) {
  // A 3-D grid written in blocks that cut rows and planes anywhere, against one write: the same
  // file, byte for byte, and every value where row-major order puts it.
  const fs::path base = fresh_dir("sweep-h5");
  fs::create_directories(base);
  SweepH5Layout layout;
  const std::size_t shape[3] = {3, 4, 5};
  for (std::size_t a = 0; a < 3; ++a)
    layout.axes.push_back({"axis" + std::to_string(a), "mm", "an axis", shape[a], [a](std::size_t i) { return 10.0 * a + i; }});
  layout.columns = {{"x", "mV", "the point's index", false}, {"y", "%", "minus it, NaN at 7", true}};
  layout.attributes = {{"command", "polrig sweep …"}, {"rig_text", "a: 1\n"}};
  const std::size_t n = layout.points();
  ASSERT_EQ(n, 60u);
  const auto values = [](std::size_t first, std::size_t count) {
    std::vector<double> v(2 * count);
    for (std::size_t k = 0; k < count; ++k) {
      v[k] = static_cast<double>(first + k);
      v[count + k] = first + k == 7 ? std::nan("") : -static_cast<double>(first + k);
    }
    return v;
  };
  const std::vector<std::vector<std::size_t>> partitions = {{60}, {7, 13, 1, 19, 20}, {1, 1, 3, 4, 5, 6, 40}};
  std::vector<std::string> files;
  for (std::size_t p = 0; p < partitions.size(); ++p) {
    const fs::path path = base / ("p" + std::to_string(p) + ".h5");
    std::optional<SweepH5Writer> w;
    w.emplace(SweepH5Writer::create(path, layout));
    std::size_t first = 0;
    for (std::size_t count : partitions[p]) {
      if (p == 2 && first == 5) {  // resuming: the file closed and reopened between blocks
        w->close();
        w.reset();
        w.emplace(SweepH5Writer::reopen(path, layout));
      }
      w->write(first, count, values(first, count));
      first += count;
    }
    w->close();
    files.push_back(read_file(path));
  }
  EXPECT_TRUE(files[0] == files[1]) << "the file depends on the block sizes";
  EXPECT_TRUE(files[0] == files[2]) << "the file depends on closing and reopening";
  const SweepH5Reader r(base / "p1.h5");
  std::vector<double> x(n), y(n);
  r.read("x", 0, x);
  r.read("y", 0, y);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(x[i], static_cast<double>(i));
    if (i == 7) EXPECT_TRUE(std::isnan(y[i]));
    else EXPECT_EQ(y[i], -static_cast<double>(i));
  }
  std::vector<double> part(11);
  r.read("x", 23, part);
  EXPECT_EQ(part.front(), 23.0);
  EXPECT_EQ(part.back(), 33.0);
  EXPECT_THROW(SweepH5Writer::create(base / "p0.h5", layout), std::runtime_error);  // never replaced
  fs::remove_all(base);
}

TEST(OutputDir, RefusesToReplaceWithoutForce) {
  const fs::path base = fresh_dir("replace");
  const fs::path dest = base / "out";
  fs::create_directories(dest);
  write_text_file(dest / "old.txt", "old");
  EXPECT_THROW(OutputDir(dest, false), std::runtime_error);
  EXPECT_EQ(read_file(dest / "old.txt"), "old");
  {
    OutputDir out(dest, true);
    write_text_file(out.staging() / "new.txt", "new");
    EXPECT_EQ(read_file(dest / "old.txt"), "old");  // untouched until commit
    out.commit();
  }
  EXPECT_FALSE(fs::exists(dest / "old.txt"));
  EXPECT_EQ(read_file(dest / "new.txt"), "new");
  fs::remove_all(base);
}

// The message of the std::runtime_error `f` throws ("" if it throws none).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(OutputDir, NeverReplacesAFolderThatAppearedDuringTheRun) {
  const fs::path base = fresh_dir("race");
  const fs::path dest = base / "new" / "out";
  {
    OutputDir out(dest, false);
    write_text_file(out.staging() / "result.csv", "x\n1\n");
    // Another run (or the user) creates the folder while this one computes.
    fs::create_directories(dest);
    write_text_file(dest / "theirs.txt", "theirs");
    const std::string msg = error_of([&] { out.commit(); });
    EXPECT_NE(msg.find(dest.string() + ": the output folder appeared while polrig was computing"),
              std::string::npos) << msg;
  }
  EXPECT_EQ(read_file(dest / "theirs.txt"), "theirs");
  EXPECT_FALSE(fs::exists(dest / "result.csv"));
  for (const auto& e : fs::directory_iterator(dest.parent_path()))
    EXPECT_EQ(e.path().filename(), "out") << "the staging folder was left behind";
  fs::remove_all(base);
}

TEST(OutputDir, ForceReplacesAFolderThatAppearedDuringTheRun) {
  const fs::path base = fresh_dir("race-force");
  const fs::path dest = base / "out";
  {
    OutputDir out(dest, true);
    write_text_file(out.staging() / "result.csv", "x\n1\n");
    fs::create_directories(dest / "sub");
    write_text_file(dest / "sub" / "theirs.txt", "theirs");
    out.commit();
  }
  EXPECT_EQ(read_file(dest / "result.csv"), "x\n1\n");
  EXPECT_FALSE(fs::exists(dest / "sub"));
  EXPECT_EQ(std::distance(fs::directory_iterator(base), fs::directory_iterator()), 1);
  fs::remove_all(base);
}

TEST(OutputDir, RenameExchangeSwapsTwoFoldersAndNoReplaceRefuses) {
  const fs::path base = fresh_dir("exchange");
  fs::create_directories(base / "a");
  fs::create_directories(base / "b");
  write_text_file(base / "a" / "f", "A");
  write_text_file(base / "b" / "f", "B");
  EXPECT_EQ(rename_no_replace(base / "a", base / "b"), EEXIST);
  EXPECT_EQ(read_file(base / "b" / "f"), "B");
  ASSERT_EQ(rename_exchange(base / "a", base / "b"), 0);
  EXPECT_EQ(read_file(base / "a" / "f"), "B");
  EXPECT_EQ(read_file(base / "b" / "f"), "A");
  EXPECT_EQ(rename_exchange(base / "a", base / "missing"), ENOENT);
  EXPECT_EQ(rename_no_replace(base / "a", base / "c"), 0);
  EXPECT_EQ(read_file(base / "c" / "f"), "B");
  fs::remove_all(base);
}

TEST(OutputDir, ForcedReplacementLeavesTheFolderPresentAtEveryInstant) {
  // A watcher looks for the folder as fast as it can while it is replaced 200 times; two
  // renames (old away, new in) would leave a moment without it.
  const fs::path base = fresh_dir("always");
  const fs::path dest = base / "out";
  fs::create_directories(dest);
  std::atomic<bool> stop{false};
  std::atomic<long> looks{0}, missing{0};
  std::thread watcher([&] {
    while (!stop) {
      if (::access(dest.c_str(), F_OK) != 0) ++missing;
      ++looks;
    }
  });
  for (int k = 0; k < 200; ++k) {
    OutputDir out(dest, true);
    write_text_file(out.staging() / "k.txt", std::to_string(k));
    out.commit();
  }
  stop = true;
  watcher.join();
  EXPECT_EQ(missing, 0) << "the folder was missing in " << missing << " of " << looks << " looks";
  EXPECT_GT(looks, 200);
  EXPECT_EQ(read_file(dest / "k.txt"), "199");
  fs::remove_all(base);
}

TEST(OutputDir, BadNamesFailClearlyAndLeaveNoParentsBehind) {
  const fs::path base = fresh_dir("names");
  fs::create_directories(base);
  // 245 bytes fit a folder but not its staging folder ".NAME.partial-PID".
  const std::string long_name(245, 'a');
  std::string msg = error_of([&] { OutputDir(base / "p" / "q" / long_name, false); });
  EXPECT_NE(msg.find("the folder name is 245 bytes long; at most"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(base / "p")) << "a parent folder was created";
  // A parent whose name is too long: the parents created before it are removed again.
  msg = error_of([&] { OutputDir(base / "p" / std::string(300, 'b') / "out", false); });
  EXPECT_NE(msg.find("the file system allows"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(base / "p"));
  // A parent that exists only as a dangling symbolic link cannot hold the folder.
  fs::create_symlink(base / "nowhere", base / "dangling");
  msg = error_of([&] { OutputDir(base / "dangling" / "x" / "out", false); });
  EXPECT_NE(msg.find("a symbolic link to '" + (base / "nowhere").string() + "', which does not exist"),
            std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(base / "nowhere"));
  // A dangling symbolic link as the destination is an existing path: refused without force.
  msg = error_of([&] { OutputDir(base / "dangling", false); });
  EXPECT_NE(msg.find("the output folder exists (a symbolic link to"), std::string::npos) << msg;
  EXPECT_TRUE(fs::is_symlink(base / "dangling"));
  msg = error_of([&] { OutputDir(fs::path(), false); });
  EXPECT_NE(msg.find("the output folder's name is empty"), std::string::npos) << msg;
  EXPECT_EQ(std::distance(fs::directory_iterator(base), fs::directory_iterator()), 1);
  fs::remove_all(base);
}

TEST(TextFile, AFullDiskIsReportedWithTheSystemsReason) {
  const std::string msg = error_of([] { write_text_file("/dev/full", std::string(100000, 'x')); });
  EXPECT_NE(msg.find("/dev/full: cannot write the file: No space left on device"), std::string::npos)
      << msg;
  // A small file fails only when it is flushed at close.
  const std::string small = error_of([] { write_text_file("/dev/full", "x\n"); });
  EXPECT_NE(small.find("No space left on device"), std::string::npos) << small;
  const std::string exr = error_of([] {
    write_exr("/dev/full", 64, 64, {{"Y", std::vector<float>(64 * 64, 1.0f)}});
  });
  EXPECT_NE(exr.find("/dev/full: cannot write the EXR image"), std::string::npos) << exr;
  EXPECT_NE(exr.find("No space left on device"), std::string::npos) << exr;
  const std::string missing = error_of([] { write_text_file("/nonexistent-polrig/x.csv", "x"); });
  EXPECT_NE(missing.find("/nonexistent-polrig/x.csv: cannot create the file: No such file or directory"),
            std::string::npos) << missing;
}

TEST(TextFile, ContinuingAFileShorterThanItsCheckpointIsRefusedNotPadded) {
  const fs::path dir = fresh_dir("textfile-resume");
  fs::create_directories(dir);
  const fs::path f = dir / "sweep.csv";
  write_text_file(f, "a,b\n1,2\n");  // 8 bytes
  {
    TextFileWriter w(f, 4);  // cut after the header, then continue
    w.write("3,4\n");
  }
  EXPECT_EQ(read_file(f), "a,b\n3,4\n");
  const std::string msg = error_of([&] { TextFileWriter(f, 20); });
  EXPECT_NE(msg.find(f.string() + ": 8 bytes, shorter than its last checkpoint (20 bytes)"), std::string::npos)
      << msg;
  EXPECT_EQ(read_file(f), "a,b\n3,4\n");  // untouched: no zero bytes appended
  fs::remove_all(dir);
}

TEST(Manifest, NamesEveryFileWithItsSchema) {
  const fs::path dir = fresh_dir("manifest");
  fs::create_directories(dir);
  write_manifest(dir, {"polrig study adc -o x", nullptr, {{"accuracy_limit.csv", 1, "limits"}}});
  const std::string m = read_file(dir / "manifest.yaml");
  EXPECT_NE(m.find("accuracy_limit.csv:"), std::string::npos);
  EXPECT_NE(m.find("schema: 1"), std::string::npos);
  EXPECT_NE(m.find("git_revision:"), std::string::npos);
  EXPECT_NE(m.find("command: polrig study adc -o x"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "rig.yaml"));  // no rig, no rig file
  fs::remove_all(dir);
}

}  // namespace
}  // namespace polrig

namespace polrig {

// Issue 23 §5.1: the size a header claims is checked before any pixel is allocated. A 64-byte-per-
// line file claiming 100000² px would need 40 GB per channel; it is refused by its header alone,
// naming the file, against the size expected or, with none, against the cameras' limit.
TEST(Exr, AHeaderClaimingAnotherSizeIsRefusedBeforeItsPixelsAreAllocated) {
  const fs::path dir = fresh_dir("exr-claimed-size");
  fs::create_directories(dir);
  const fs::path file = dir / "frame.exr";
  ExrImage image;
  image.width = 8, image.height = 6;
  image.floats.push_back({"AoP", std::vector<float>(48, 1.0f)});
  image.uints.push_back({"raw.000", std::vector<std::uint32_t>(48, 7)});
  write_exr_image(file, image);
  EXPECT_EQ(read_exr_image(file, ExrSize{8, 6}).uints[0].pixels[47], 7u);
  test::claim_exr_size(file, 100000, 100000);
  const auto refusal = [&](const std::function<void()>& read) {
    try {
      read();
    } catch (const DataError& e) {
      return std::string(e.what());
    } catch (const std::exception& e) {
      return "not a DataError: " + std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string expected = file.string() + ": 100000 × 100000 px (expected 8 × 6)";
  EXPECT_EQ(refusal([&] { read_exr_image(file, ExrSize{8, 6}); }), expected);
  EXPECT_EQ(refusal([&] { read_exr_rows(file, 0, 1, nullptr, ExrSize{8, 6}); }), expected);
  int w = 0, h = 0;
  EXPECT_EQ(refusal([&] { read_exr(file, w, h, ExrSize{8, 6}); }), expected);
  const std::string limit = file.string() + ": 100000 × 100000 px (expected at most 16384 × 16384)";
  EXPECT_EQ(refusal([&] { read_exr_image(file); }), limit);
  EXPECT_EQ(refusal([&] { read_exr(file, w, h); }), limit);
  fs::remove_all(dir);
}

}  // namespace polrig

namespace polrig {

// ExrThreads: an image compressed on OpenEXR's pool or on the calling thread alone is the same
// file, and reads back to the pixels written either way, also two images at once on two threads
// (as side_by_side.h's stops read them). 200 rows: 13 ZIP and 7 PIZ line blocks.
TEST(Exr, OnThisThreadOrOnThePoolTheSameBytesAndPixels) {
  const fs::path dir = fresh_dir("exr-threads");
  fs::create_directories(dir);
  ExrImage image;
  image.width = 64, image.height = 200;
  std::vector<float> aop(64 * 200);
  std::vector<std::uint32_t> raw(aop.size());
  for (std::size_t i = 0; i < aop.size(); ++i) {
    aop[i] = static_cast<float>(std::fmod(0.37 * static_cast<double>(i * i % 9973), 180.0));
    raw[i] = static_cast<std::uint32_t>((i * 2654435761u) % 4096u);
  }
  image.floats.push_back({"AoP", aop});
  image.uints.push_back({"raw.000", raw});
  for (ExrCompression c : {ExrCompression::Zip, ExrCompression::Piz}) {
    const fs::path pooled = dir / "pooled.exr", here = dir / "here.exr";
    write_exr_image(pooled, image, c, ExrThreads::Pool);
    write_exr_image(here, image, c, ExrThreads::ThisThread);
    EXPECT_EQ(read_file(pooled), read_file(here));
    std::array<ExrImage, 2> back;
    std::thread other([&] { back[1] = read_exr_image(here, ExrSize{64, 200}, ExrThreads::ThisThread); });
    back[0] = read_exr_image(pooled, ExrSize{64, 200}, ExrThreads::ThisThread);
    other.join();
    for (const ExrImage& b : back) {
      EXPECT_EQ(b.floats.at(0).pixels, aop);
      EXPECT_EQ(b.uints.at(0).pixels, raw);
    }
    EXPECT_EQ(read_exr_image(here, ExrSize{64, 200}, ExrThreads::Pool).uints.at(0).pixels, raw);
    const ExrImage band = read_exr_rows(here, 70, 50, nullptr, ExrSize{64, 200}, ExrThreads::ThisThread);
    EXPECT_EQ(band.uints.at(0).pixels, std::vector<std::uint32_t>(raw.begin() + 70 * 64, raw.begin() + 120 * 64));
  }
  fs::remove_all(dir);
}

}  // namespace polrig
