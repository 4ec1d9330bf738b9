#pragma once
// CSV output. Numbers are written in their shortest exact form ({fmt}'s "{}"), so a CSV reads
// back to the same doubles and is byte-identical for identical results.
#include <filesystem>
#include <string>
#include <vector>

namespace polrig {

class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> header);
  void add_row(const std::vector<double>& values);
  std::size_t columns() const { return header_.size(); }
  std::size_t rows() const { return rows_; }
  std::string text() const;

 private:
  std::vector<std::string> header_;
  std::string body_;
  std::size_t rows_ = 0;
};

// Writes a whole file or throws std::runtime_error naming the path.
void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace polrig
