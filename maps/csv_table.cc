#include "maps/csv_table.h"

#include <charconv>
#include <sstream>

#include "maps/map_errors.h"

namespace plantscale::maps {
namespace {

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

}  // namespace

CsvReader::CsvReader(const std::filesystem::path& file, const std::vector<std::string>& columns)
    : file_(file), in_(file) {
  std::string header;
  if (!in_ || !std::getline(in_, header)) throw MapIoError(file.string(), "cannot be read");
  bytes_read_ = header.size() + 1;
  const std::vector<std::string> names = Split(header);
  for (size_t i = 0; i < names.size(); ++i) index_[names[i]] = i;
  for (const std::string& c : columns) {
    if (index_.count(c) == 0) throw DataError(file.string() + ": line 1: no column '" + c + "'");
  }
}

bool CsvReader::Next() {
  std::string text;
  if (!std::getline(in_, text)) return false;
  ++line_;
  bytes_read_ += text.size() + 1;
  cells_ = Split(text);
  if (cells_.size() < index_.size()) {
    throw DataError(file_.string() + ": line " + std::to_string(line_) + ": " +
                    std::to_string(cells_.size()) + " cells, the header has " +
                    std::to_string(index_.size()));
  }
  return true;
}

std::string CsvReader::Where(const std::string& column) const {
  return file_.string() + ": line " + std::to_string(line_) + ", column " + column;
}

const std::string& CsvReader::Text(const std::string& column) const {
  return cells_.at(index_.at(column));
}

double CsvReader::Number(const std::string& column) const {
  const std::string& s = Text(column);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size()) {
    throw DataError(Where(column) + ": '" + s + "' is not a number");
  }
  return value;
}

int64_t CsvReader::Integer(const std::string& column) const {
  const std::string& s = Text(column);
  int64_t value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || end != s.data() + s.size()) {
    throw DataError(Where(column) + ": '" + s + "' is not an integer");
  }
  return value;
}

}  // namespace plantscale::maps
