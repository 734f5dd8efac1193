// Links the recognition core alone (configured, not built, by the package test).
#include "viewpose/recognize/recognizer.hpp"

int main() { return viewpose::RecognizerOptions{}.match.per_object > 0 ? 0 : 1; }
