// The file the libraries' and the tests' precompiled headers are made with (cmake/PrecompiledHeaders.cmake):
// nothing of its own
