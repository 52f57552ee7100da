// The guest program of the plugin's test: `insn_count_probe N` runs the same loop body N times,
// so the guest instructions of N, 2N and 3N runs grow by one fixed amount each.
#include <cstdlib>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const long n = std::strtol(argv[1], nullptr, 10);
  volatile unsigned sum = 0;
  for (long i = 0; i < n; ++i) sum = sum + static_cast<unsigned>(i);
  return 0;
}
