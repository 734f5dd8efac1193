#pragma once
// VIEWPOSE_CLONES before a function compiles it twice, for AVX2 and for any x86-64, and the
// processor picks one when the program is loaded: for the few loops that vectorize and are
// measured to matter (the normals' neighbour sums, the CRH roll search's harmonics). AVX2 does not
// imply fused multiply-adds: a loop whose elements are computed apart (the harmonics) gives the
// same bits in both versions; a sum across elements (the normals') is added in another order.
// (With VIEWPOSE_NATIVE the baseline version may fuse them too; crh.cpp is compiled with
// -ffp-contract=off, so its bits stay the same there as well.)
//
// ThreadSanitizer instruments the resolver that picks a clone, which runs while the program is
// being loaded, before the sanitizer's runtime exists: the program crashed before main. Under it
// (gcc's __SANITIZE_THREAD__, clang's __has_feature) only the baseline version is built.
#if defined(__SANITIZE_THREAD__)
#define VIEWPOSE_CLONES
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define VIEWPOSE_CLONES
#endif
#endif
#ifndef VIEWPOSE_CLONES
#define VIEWPOSE_CLONES [[gnu::target_clones("avx2", "default")]]
#endif
