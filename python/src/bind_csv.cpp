// Python binding of the joint-log reader's fast path: the data rows of a CSV of decimal numbers
// parsed at once, on two threads, without the interpreter lock.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <charconv>
#include <cstring>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

namespace py = pybind11;

namespace {

bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isBlank(char c) { return c == ' ' || c == '\t'; }

// One cell [b, e): ASCII blanks, a decimal number (optional sign, digits with an optional point,
// optional exponent), ASCII blanks; its value, correctly rounded, into `out`. False for anything
// else, and for a value out of the range of a double (overflow, or an underflow from_chars
// reports): the strict reader then decides.
bool parseCell(const char* b, const char* e, double& out) {
  while (b < e && isBlank(*b)) ++b;
  while (e > b && isBlank(e[-1])) --e;
  const char* p = b;
  if (p < e && (*p == '+' || *p == '-')) ++p;
  const char* digits = p;
  while (p < e && isDigit(*p)) ++p;
  bool mantissa = p > digits;
  if (p < e && *p == '.') {
    const char* fraction = ++p;
    while (p < e && isDigit(*p)) ++p;
    mantissa = mantissa || p > fraction;
  }
  if (!mantissa) return false;
  if (p < e && (*p == 'e' || *p == 'E')) {
    ++p;
    if (p < e && (*p == '+' || *p == '-')) ++p;
    const char* exponent = p;
    while (p < e && isDigit(*p)) ++p;
    if (p == exponent) return false;
  }
  if (p != e) return false;
  const char* s = *b == '+' ? b + 1 : b;  // from_chars takes no '+'
  const auto [end, ec] = std::from_chars(s, e, out);
  return ec == std::errc() && end == e;
}

// The lines of [b, e) (LF or CR LF ends) as rows of `columns` cells appended to `out`; lines of
// blanks only are skipped, as the strict reader skips them. False at the first thing off.
bool parseRows(const char* b, const char* e, long columns, std::vector<double>& out) {
  while (b < e) {
    const char* nl = static_cast<const char*>(std::memchr(b, '\n', static_cast<size_t>(e - b)));
    const char* end = nl ? nl : e;
    const char* next = nl ? nl + 1 : e;
    if (end > b && end[-1] == '\r') --end;
    const char* q = b;
    while (q < end && isBlank(*q)) ++q;
    if (q == end) {
      b = next;
      continue;
    }
    long c = 0;
    for (const char* cell = b;; ++c) {
      const char* comma =
          static_cast<const char*>(std::memchr(cell, ',', static_cast<size_t>(end - cell)));
      const char* stop = comma ? comma : end;
      double v;
      if (c == columns || !parseCell(cell, stop, v)) return false;
      out.push_back(v);
      if (!comma) break;
      cell = comma + 1;
    }
    if (c + 1 != columns) return false;
    b = next;
  }
  return true;
}

}  // namespace

void bindCsv(py::module_& m) {
  m.def(
      "parse_csv_numbers",
      [](const py::bytes& data, long columns) -> py::object {
        const std::string_view text = data;
        std::vector<double> first, second;
        bool ok = true;
        {
          py::gil_scoped_release release;
          const char* b = text.data();
          const char* e = b + text.size();
          // two halves cut after a line end, parsed side by side when the block is large
          const char* mid = text.size() < (1u << 20) ? e : b + text.size() / 2;
          if (mid < e) {
            const void* nl = std::memchr(mid, '\n', static_cast<size_t>(e - mid));
            mid = nl ? static_cast<const char*>(nl) + 1 : e;
          }
          bool ok2 = true;
          std::thread other;
          if (mid < e) other = std::thread([&] { ok2 = parseRows(mid, e, columns, second); });
          ok = parseRows(b, mid, columns, first);
          if (other.joinable()) other.join();
          ok = ok && ok2;
        }
        if (!ok || columns < 1) return py::none();
        const auto rows = static_cast<py::ssize_t>((first.size() + second.size()) / columns);
        py::array_t<double> out({rows, static_cast<py::ssize_t>(columns)});
        double* p = out.mutable_data();
        std::memcpy(p, first.data(), first.size() * sizeof(double));
        std::memcpy(p + first.size(), second.data(), second.size() * sizeof(double));
        return std::move(out);
      },
      py::arg("data"), py::arg("columns"),
      "The rows of `data` (bytes: lines of `columns` comma-separated decimal numbers, blanks "
      "around them, LF or CR LF line ends, lines of blanks skipped) as an array (rows, columns), "
      "each value correctly rounded as Python's float() gives it; None when anything else is "
      "met (another character or spelling, a row of another length, a value out of the range of "
      "a double).");
}
