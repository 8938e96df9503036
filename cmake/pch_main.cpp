// The file the programs' precompiled headers are made with (cmake/PrecompiledHeaders.cmake): an empty program.
// No macro may tell it from the others: a macro defined where the headers were precompiled and not where they are
// read makes GCC refuse them (-Winvalid-pch)
int main() { return 0; }
