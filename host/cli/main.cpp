// Placeholder until the CLI lands.
#include <cstdio>
int main() { std::puts("clbdpt: not yet"); return 1; }
