#pragma once
// GDAL plumbing private to ingest: one-time driver registration, quiet error
// handling (GDAL's messages are turned into Error values), and RAII handles.
#include <gdal.h>

#include <memory>
#include <string>

namespace relief::ingest {

// Registers drivers and silences GDAL's stderr output. Safe to call often.
void init_gdal();
// The last GDAL error message of this thread, or `fallback` when there is none.
std::string gdal_error(const std::string& fallback);

struct DatasetCloser {
  void operator()(GDALDatasetH h) const {
    if (h) GDALClose(h);
  }
};
using Dataset = std::unique_ptr<std::remove_pointer_t<GDALDatasetH>, DatasetCloser>;

// Opens a raster read-only; nullptr on failure (see gdal_error()).
Dataset open_raster(const std::string& path);

}  // namespace relief::ingest
