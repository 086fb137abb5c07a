#include "wobble/formats/heightfield_file.h"

#include <cmath>
#include <sstream>
#include <vector>

#include "wobble/core/errors.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/formats/line_reader.h"
#include "wobble/formats/parse_error.h"

namespace wobble::formats {

namespace {

// The words of a line, commas taken as blanks.
std::vector<std::string> Words(std::string line) {
  for (char& c : line)
    if (c == ',' || c == '\t' || c == '\r') c = ' ';
  std::istringstream in(line);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

}  // namespace

std::shared_ptr<const Heightfield> ReadHeightfieldFile(const std::string& path) {
  return detail::WithFile(path, [&](std::istream& in) {
    bool has_origin = false, has_spacing = false;
    Eigen::Vector2d origin, spacing;
    std::vector<double> heights;
    int nx = 0, nz = 0, number = 0, first_row = 0;
    struct Region {
      int line;
      Eigen::Vector2d lo, hi;
      SurfaceOverrides constants;
    };
    std::vector<Region> regions;  // applied once the grid is read
    auto pair = [&](const std::vector<std::string>& w, const char* what, Eigen::Vector2d* out) {
      if (w.size() != 3 || !detail::ParseNumber(w[1], &out->x()) || !detail::ParseNumber(w[2], &out->y()))
        throw ParseError(path, number, std::string("expected '") + what + "' and two numbers");
    };
    for (std::string line; std::getline(in, line);) {
      ++number;
      const size_t hash = line.find('#');
      const std::vector<std::string> w = Words(hash == std::string::npos ? line : line.substr(0, hash));
      if (w.empty()) continue;
      if (w[0] == "origin") {
        if (nz > 0) throw ParseError(path, number, "'origin' comes before the rows of heights");
        pair(w, "origin X0 Z0", &origin);
        has_origin = true;
        continue;
      }
      if (w[0] == "spacing") {
        if (nz > 0) throw ParseError(path, number, "'spacing' comes before the rows of heights");
        pair(w, "spacing DX DZ", &spacing);
        if (!(spacing.x() > 0 && spacing.y() > 0)) throw ParseError(path, number, "expected a spacing > 0 along x and z");
        has_spacing = true;
        continue;
      }
      if (!has_origin || !has_spacing)
        throw ParseError(path, number, "expected 'origin X0 Z0' and 'spacing DX DZ' before the rows of heights");
      if (w[0] == "region") {
        const std::string usage = "expected 'region X0 Z0 X1 Z1 NAME VALUE [NAME VALUE ...]' (NAME: grconst, grdam, "
                                  "frconst, frsin)";
        if (w.size() < 7 || w.size() % 2 == 0) throw ParseError(path, number, usage);
        Region r{number, {}, {}, {}};
        double box[4];
        for (int k = 0; k < 4; ++k)
          if (!detail::ParseNumber(w[size_t(k + 1)], &box[k]))
            throw ParseError(path, number, usage + ", got '" + w[size_t(k + 1)] + "'");
        r.lo = Eigen::Vector2d(box[0], box[1]);
        r.hi = Eigen::Vector2d(box[2], box[3]);
        for (size_t i = 5; i + 1 < w.size(); i += 2) {
          double value;
          if (!detail::ParseNumber(w[i + 1], &value))
            throw ParseError(path, number, "expected a number for " + w[i] + ", got '" + w[i + 1] + "'");
          if (!r.constants.Set(w[i], value))
            throw ParseError(path, number, "expected grconst, grdam, frconst or frsin, got '" + w[i] + "'");
        }
        regions.push_back(r);
        continue;
      }
      if (nz == 0) {
        nx = int(w.size());
        first_row = number;
        if (nx < 2) throw ParseError(path, number, "expected at least two heights in a row");
      } else if (int(w.size()) != nx) {
        throw ParseError(path, number, "expected " + std::to_string(nx) + " heights, as the first row (line " +
                                           std::to_string(first_row) + "), got " + std::to_string(w.size()));
      }
      for (size_t i = 0; i < w.size(); ++i) {
        double h;
        if (!detail::ParseNumber(w[i], &h))
          throw ParseError(path, number, "expected a height, got '" + w[i] + "' (column " + std::to_string(i + 1) + ")");
        heights.push_back(h);
      }
      ++nz;
    }
    if (nz < 2) throw ParseError(path, number, "expected at least two rows of heights, got " + std::to_string(nz));
    std::shared_ptr<const Heightfield> field;
    try {
      field = Heightfield::Make(origin, spacing, nx, nz, std::move(heights));
    } catch (const InputError& e) {
      throw ParseError(path, first_row, e.what());
    }
    for (const Region& r : regions) {
      try {
        field = field->WithRegion(r.lo, r.hi, r.constants);
      } catch (const InputError& e) {
        throw ParseError(path, r.line, e.what());
      }
    }
    return field;
  });
}

void WriteHeightfieldFile(const std::string& path, const Heightfield& field) {
  std::ostringstream s;
  s.precision(17);  // read back bit for bit
  s << "# wobble heightfield: y = h(x, z); a row of heights per z, from x0 by dx\n";
  s << "origin " << field.origin().x() << " " << field.origin().y() << "\n";
  s << "spacing " << field.spacing().x() << " " << field.spacing().y() << "\n";
  for (int j = 0; j < field.nz(); ++j) {
    for (int i = 0; i < field.nx(); ++i) s << (i ? "," : "") << field.Node(i, j);
    s << "\n";
  }
  // a cell's own constants as a region of that cell alone (its centre is inside its bounds)
  for (int j = 0; j + 1 < field.nz(); ++j)
    for (int i = 0; i + 1 < field.nx(); ++i) {
      const SurfaceOverrides& c = field.CellOverrides(i + (field.nx() - 1) * j);
      const double values[] = {c.stiffness, c.normal_damping, c.friction_damping, c.friction_cap};
      std::string set;
      for (size_t k = 0; k < 4; ++k)
        if (!std::isnan(values[k])) {
          std::ostringstream v;
          v.precision(17);
          v << " " << SurfaceOverrides::Names()[k] << " " << values[k];
          set += v.str();
        }
      if (set.empty()) continue;
      const Eigen::Vector2d lo = field.origin() + field.spacing().cwiseProduct(Eigen::Vector2d(i, j));
      const Eigen::Vector2d hi = field.origin() + field.spacing().cwiseProduct(Eigen::Vector2d(i + 1, j + 1));
      s << "region " << lo.x() << " " << lo.y() << " " << hi.x() << " " << hi.y() << set << "\n";
    }
  WriteTextAtomically(path, s.str());
}

}  // namespace wobble::formats
