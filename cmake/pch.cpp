// The translation unit that builds a precompiled header of the libraries or programs
// (CMakeLists.txt, PBNBV_PCH).
