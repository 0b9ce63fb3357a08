// Python binding of the zero-phase filter's inner loop: cascaded second-order sections run along
// the rows of a block of samples (time down the rows, signals across the columns), all columns at
// once, without the interpreter lock. Per column the arithmetic is that of
// scipy.signal.sosfilt (transposed direct form II, sections in order within each sample), so the
// values are the same; the columns side by side let the compiler vectorise across them.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <string>
#include <vector>

namespace py = pybind11;

namespace {

bool isDoubles(const py::array& a) { return a.dtype().is(py::dtype::of<double>()); }

// Refuses what the loop could not read safely: the wrong element type, shapes that do not match,
// columns that are not adjacent in memory.
void require(bool ok, const std::string& what) {
  if (!ok) throw py::value_error("sosfilt_rows: " + what);
}

}  // namespace

void bindFilter(py::module_& m) {
  m.def(
      "sosfilt_rows",
      [](const py::array& sos, const py::array& x, py::array& z, const py::object& cols_obj,
         const py::object& out_obj) {
        require(isDoubles(sos) && sos.ndim() == 2 && sos.shape(1) == 6 &&
                    sos.strides(1) == sizeof(double),
                "sos must be float64 (sections, 6) with adjacent columns");
        const py::ssize_t sections = sos.shape(0);
        require(
            isDoubles(x) && x.ndim() == 2 && (x.shape(1) <= 1 || x.strides(1) == sizeof(double)),
            "x must be float64 (samples, columns) with adjacent columns");
        const py::ssize_t rows = x.shape(0), width = x.shape(1);
        std::vector<std::int64_t> cols;
        if (!cols_obj.is_none()) {
          const auto c = py::array_t<std::int64_t, py::array::forcecast>::ensure(cols_obj);
          require(c && c.ndim() == 1, "cols must be a 1-d array of column indices");
          const auto r = c.unchecked<1>();
          for (py::ssize_t j = 0; j < r.shape(0); ++j) {
            require(r(j) >= 0 && r(j) < width, "a column index is out of range");
            cols.push_back(r(j));
          }
        }
        const py::ssize_t w = cols_obj.is_none() ? width : static_cast<py::ssize_t>(cols.size());
        require(isDoubles(z) && z.ndim() == 3 && z.shape(0) == sections && z.shape(1) == 2 &&
                    z.shape(2) == w && z.writeable() && (z.flags() & py::array::c_style) != 0,
                "z must be a writable C-contiguous float64 (sections, 2, columns)");
        char* out = nullptr;
        py::ssize_t outStride = 0;
        if (!out_obj.is_none()) {
          auto o = py::reinterpret_borrow<py::array>(out_obj);
          require(isDoubles(o) && o.ndim() == 2 && o.shape(0) == rows && o.shape(1) == w &&
                      o.writeable() && (w <= 1 || o.strides(1) == sizeof(double)),
                  "out must be a writable float64 (samples, columns) with adjacent columns");
          out = static_cast<char*>(o.mutable_data());
          outStride = o.strides(0);
        }
        const auto* s = static_cast<const char*>(sos.data());
        const py::ssize_t sosStride = sos.strides(0);
        const auto* in = static_cast<const char*>(x.data());
        const py::ssize_t inStride = x.strides(0);
        double* state = static_cast<double*>(z.mutable_data());
        {
          py::gil_scoped_release release;
          std::vector<double> coef(static_cast<size_t>(6 * sections));
          for (py::ssize_t k = 0; k < sections; ++k)
            for (int c = 0; c < 6; ++c)
              coef[static_cast<size_t>(6 * k + c)] =
                  reinterpret_cast<const double*>(s + k * sosStride)[c];
          std::vector<double> cur(static_cast<size_t>(w));
          for (py::ssize_t i = 0; i < rows; ++i) {
            const auto* row = reinterpret_cast<const double*>(in + i * inStride);
            double* __restrict xc = cur.data();
            if (cols.empty())
              for (py::ssize_t j = 0; j < w; ++j) xc[j] = row[j];
            else
              for (py::ssize_t j = 0; j < w; ++j) xc[j] = row[cols[static_cast<size_t>(j)]];
            for (py::ssize_t k = 0; k < sections; ++k) {
              const double* c = &coef[static_cast<size_t>(6 * k)];
              const double b0 = c[0], b1 = c[1], b2 = c[2], a1 = c[4], a2 = c[5];
              double* __restrict z0 = state + (2 * k) * w;
              double* __restrict z1 = state + (2 * k + 1) * w;
              // scipy.signal.sosfilt's update, in its order of operations
              for (py::ssize_t j = 0; j < w; ++j) {
                const double xn = b0 * xc[j] + z0[j];
                z0[j] = b1 * xc[j] - a1 * xn + z1[j];
                z1[j] = b2 * xc[j] - a2 * xn;
                xc[j] = xn;
              }
            }
            if (out) {
              auto* o = reinterpret_cast<double*>(out + i * outStride);
              for (py::ssize_t j = 0; j < w; ++j) o[j] = xc[j];
            }
          }
        }
      },
      py::arg("sos"), py::arg("x"), py::arg("z"), py::arg("cols") = py::none(),
      py::arg("out") = py::none(),
      "Second-order sections `sos` (sections, 6; a0 = 1) run down the rows of `x` (samples, "
      "columns; rows in any order, e.g. reversed, columns adjacent), on the columns `cols` of "
      "`x` (all when None), from the state `z` (sections, 2, columns), which is updated in "
      "place; the output is written into `out` (samples, columns; it may be `x` itself) unless "
      "None. Per column the values are scipy.signal.sosfilt's.");
}
