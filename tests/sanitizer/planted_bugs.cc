// Bugs planted on purpose, one per sanitizer the build promises (ASan, UBSan, LSan): each must
// be reported and must stop the program, or the sanitizer build's clean test run proves nothing.
// Built and run only in the sanitizer build (tests/sanitizer/CMakeLists.txt).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

namespace {

// volatile: the optimiser must not fold the bugs away or prove them at compile time.
volatile int g_index = 8;
volatile int g_big = std::numeric_limits<int>::max();
char* volatile g_sink = nullptr;

int HeapOverflow() {
  int* values = new int[8];
  const int value = values[g_index];  // one past the end
  delete[] values;
  return value;
}

int SignedOverflow() { return g_big + 1; }

int Leak() {
  g_sink = static_cast<char*>(std::malloc(64));
  std::strcpy(g_sink, "never freed");
  g_sink = nullptr;  // the only pointer is gone: LeakSanitizer reports it at exit
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const char* bug = argc > 1 ? argv[1] : "";
  int result = 0;
  if (std::strcmp(bug, "heap-overflow") == 0) {
    result = HeapOverflow();
  } else if (std::strcmp(bug, "signed-overflow") == 0) {
    result = SignedOverflow();
  } else if (std::strcmp(bug, "leak") == 0) {
    return Leak();  // LeakSanitizer reports at exit
  } else {
    std::fprintf(stderr, "usage: %s heap-overflow|signed-overflow|leak\n", argv[0]);
    return 2;
  }
  // Reached only when the sanitizer let the program go on after its report, or saw nothing.
  std::printf("not halted (%d)\n", result);
  return 0;
}
