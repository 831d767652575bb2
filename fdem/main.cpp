#include <cstdio>
int main() { std::puts("fdem " FDEM_VERSION); return 0; }
