// Default options of the sanitizer build (EMA_SANITIZE=ON, docs/reliability.md), compiled into
// every executable of that build so that ctest, a plain shell and the lead's CI all run with
// the same settings (the environment variables ASAN_OPTIONS etc. still override them).
extern "C" {

// Leaks are checked at every exit; a stack-use-after-return is caught too.
const char* __asan_default_options() { return "detect_leaks=1:detect_stack_use_after_return=1:strict_init_order=1"; }

// -fno-sanitize-recover=all already stops at the first report; print where it happened.
const char* __ubsan_default_options() { return "print_stacktrace=1:halt_on_error=1"; }

// Leaks inside system libraries that ema cannot free, one library each, with the reason.
// ema's own code gets no suppression.
//  * libfontconfig: cairo's text rendering (PLplot's svgcairo/pngcairo drivers, `ema fit --plot`)
//    fills fontconfig's pattern and font caches, which are process-lifetime and never freed;
//  * libltdl: PLplot loads its device driver with lt_dlopen and keeps the handle for the life of
//    the process (plend() does not lt_dlexit()).
// Both are allocations made and owned inside those libraries; ema's own code calls plend().
const char* __lsan_default_suppressions() {
  return "leak:libfontconfig.so\n"
         "leak:libltdl.so\n";
}

}  // extern "C"
