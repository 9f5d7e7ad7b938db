#pragma once
// Reads the simulator's own CSV files (plain comma separated, one header
// line, no quoting) by column name, with messages naming file, line, column.

#include <filesystem>
#include <fstream>
#include <string>
#include <unordered_map>
#include <vector>

namespace plantscale::maps {

class CsvReader {
 public:
  // Throws MapIoError when unreadable, DataError when a column is missing.
  CsvReader(const std::filesystem::path& file, const std::vector<std::string>& columns);

  bool Next();  // false at the end; throws DataError for a short line
  double Number(const std::string& column) const;
  int64_t Integer(const std::string& column) const;
  const std::string& Text(const std::string& column) const;
  size_t bytes_read() const { return bytes_read_; }
  size_t line() const { return line_; }

 private:
  std::string Where(const std::string& column) const;

  std::filesystem::path file_;
  std::ifstream in_;
  std::unordered_map<std::string, size_t> index_;
  std::vector<std::string> cells_;
  size_t line_ = 1;
  size_t bytes_read_ = 0;
};

}  // namespace plantscale::maps
