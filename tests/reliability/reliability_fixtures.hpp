#pragma once
// Shared helpers of the reliability tests: small scenes, temporary folders (ScratchDir), and a check
// that a run folder holds only complete, readable, finite output.
#include "../support/scratch_dir.hpp"
#include "talus/scene/scene_json.hpp"

#include <fmt/core.h>

#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace talus::test {

namespace fs = std::filesystem;

inline std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// A block sliding on a frictional floor, ~1000 particles: fast enough to run many times.
inline std::string small_slide_json(double end_time = 0.3, double checkpoint_interval = 0.02, const std::string& extra = "") {
  return fmt::format(R"({{
    "name": "small_slide",
    "grid": {{ "origin": [0, 0, 0], "size": [1.2, 0.4, 0.4], "cell_size": 0.04 }},
    "time": {{ "end": {}, "courant": 0.3 }},
    "materials": {{ "rubber": {{ "density": 1000.0, "young": 1.0e6, "poisson": 0.3 }} }},
    "bodies": [ {{ "name": "block", "material": "rubber", "box": {{ "min": [0.1, 0.1, 0.0], "max": [0.3, 0.3, 0.2] }},
                  "particles_per_cell": 2, "velocity": [2.0, 0.0, -0.5] }} ],
    "boundaries": {{ "z-": {{ "type": "friction", "friction_coefficient": 0.3 }}, "z+": "open" }},
    "output": {{ "frame_interval": 0.02, "history_interval": 0.005, "checkpoint_interval": {} }}{}
  }})", end_time, checkpoint_interval, extra);
}

/// Frames listed in a .pvd index, as paths.
inline std::vector<fs::path> pvd_frames(const fs::path& pvd) {
  const std::string xml = read_text(pvd);
  std::vector<fs::path> frames;
  const std::regex file_attr("file=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), file_attr); it != std::sregex_iterator(); ++it)
    frames.push_back(pvd.parent_path() / (*it)[1].str());
  return frames;
}

/// Reads a frame with VTK's reader; returns the number of points (0 on failure). Every value of
/// every point array must be finite.
inline long long read_frame_checked(const fs::path& path, std::string* problem) {
  if (!fs::exists(path)) {
    *problem = path.string() + " is missing";
    return 0;
  }
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.string().c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || !grid || grid->GetNumberOfPoints() == 0) {
    *problem = path.string() + " does not read";
    return 0;
  }
  vtkPointData* pd = grid->GetPointData();
  for (int a = 0; a < pd->GetNumberOfArrays(); ++a) {
    vtkDataArray* arr = pd->GetArray(a);
    if (!arr) continue;
    for (vtkIdType i = 0; i < arr->GetNumberOfTuples(); ++i)
      for (int c = 0; c < arr->GetNumberOfComponents(); ++c)
        if (!std::isfinite(arr->GetComponent(i, c))) {
          *problem = fmt::format("{}: array {} has a non-finite value", path.string(), arr->GetName());
          return 0;
        }
  }
  return grid->GetNumberOfPoints();
}

/// Every frame of the run folder reads and is finite; every energy row is complete and finite.
inline void expect_readable_run_folder(const fs::path& dir) {
  ASSERT_TRUE(fs::exists(dir / "particles.pvd")) << dir;
  const auto frames = pvd_frames(dir / "particles.pvd");
  EXPECT_FALSE(frames.empty());
  for (const auto& f : frames) {
    std::string problem;
    EXPECT_GT(read_frame_checked(f, &problem), 0) << problem;
  }
  std::ifstream history(dir / "energy.csv");
  std::string line;
  int row = 0, columns = 0;
  while (std::getline(history, line)) {
    if (row++ == 0) {
      columns = static_cast<int>(std::count(line.begin(), line.end(), ',')) + 1;
      EXPECT_EQ(line.rfind("time,step,dt,", 0), 0u) << line;
      continue;
    }
    std::stringstream ss(line);
    std::string field;
    int fields = 0;
    while (std::getline(ss, field, ',')) {
      ++fields;
      EXPECT_TRUE(std::isfinite(std::stod(field))) << "energy.csv row " << row << ": " << line;
    }
    EXPECT_EQ(fields, columns) << "energy.csv row " << row << " is incomplete: " << line;
  }
  EXPECT_GT(row, 1);
}

}  // namespace talus::test
