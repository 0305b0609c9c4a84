/* kd_float_float.h — float-float ("double-float") arithmetic: a value held as the unevaluated sum
 * hi + lo of two floats, about 48 significant bits. The triangle test's two exact steps (the
 * watertight edge fallback and the refined hit distance, core/device/kd_traverse.h) use it on
 * devices without cl_khr_fp64 (Intel Arc, Xe-LP), where double does not exist. Written once for
 * host C++ and OpenCL C, like the other shared headers, so that host tests run the device's code.
 *
 * The error-free transformations are Knuth's TwoSum and, with a fused multiply-add, TwoProduct:
 * s + e and p + e are *exactly* a + b and a * b (barring overflow, and underflow of e). The sum,
 * product and quotient are the accurate ones of Joldes, Muller & Popescu, "Tight and rigorous
 * error bounds for basic building blocks of double-word arithmetic" (ACM TOMS 44(2), 2017):
 * AccurateDWPlusDW (relative error below 3u^2), DWTimesDW (below 5u^2) and a quotient refined by
 * one Newton step (a few u^2), u = 2^-24. Their results are normalised: hi = fl(hi + lo).
 *
 * They need round-to-nearest float arithmetic that is neither contracted into FMAs nor
 * reassociated: kd_traverse.h turns FP_CONTRACT off for the device, the host build contracts
 * nothing, and nothing is compiled with fast or relaxed math (cl/renderer/opencl_renderer.cpp).
 * OpenCL requires fma() to be correctly rounded whatever the hardware, so TwoProduct is exact on
 * every device. The range is float's: values past 1e38 overflow (the caller sees a non-finite
 * result and keeps its float answer) and lo parts below 1e-38 lose bits; scenes are traced in
 * their own frame (core/scene/scene_frame.h), far from both.
 *
 * Functions hand back pairs through out pointers, as kd_traverse.h explains. */
#ifndef KDRAY_KD_FLOAT_FLOAT_H
#define KDRAY_KD_FLOAT_FLOAT_H

#include "core/device/kd_shared.h"

#ifdef KDRAY_DEVICE_CODE
#pragma OPENCL FP_CONTRACT OFF
#define KDRAY_FMA fma
#else
#include <cmath>
#define KDRAY_FMA std::fma
#endif

/* s + e = a + b exactly (Knuth's TwoSum: no condition on the operands). */
KDRAY_HOT_INLINE void kd_two_sum(kd_f32 a, kd_f32 b, kd_f32* s, kd_f32* e) {
    const kd_f32 sum = a + b;
    const kd_f32 b_part = sum - a;
    const kd_f32 a_part = sum - b_part;
    *s = sum;
    *e = (a - a_part) + (b - b_part);
}

/* s + e = a + b exactly, when |a| >= |b| or a is 0 (Dekker's FastTwoSum). */
KDRAY_HOT_INLINE void kd_fast_two_sum(kd_f32 a, kd_f32 b, kd_f32* s, kd_f32* e) {
    const kd_f32 sum = a + b;
    *s = sum;
    *e = b - (sum - a);
}

/* p + e = a * b exactly: the fused multiply-add's single rounding leaves the product's low half. */
KDRAY_HOT_INLINE void kd_two_product(kd_f32 a, kd_f32 b, kd_f32* p, kd_f32* e) {
    const kd_f32 product = a * b;
    *p = product;
    *e = KDRAY_FMA(a, b, -product);
}

/* (hi, lo) = (ah, al) + (bh, bl): AccurateDWPlusDW, exact in sign (a nonzero sum has a relative
 * error below 3u^2 < 1; an exactly zero sum of normalised operands comes out 0). */
KDRAY_HOT_INLINE void kd_ff_add(kd_f32 ah, kd_f32 al, kd_f32 bh, kd_f32 bl, kd_f32* hi,
                                kd_f32* lo) {
    kd_f32 sh, sl, th, tl, vh, vl;
    kd_two_sum(ah, bh, &sh, &sl);
    kd_two_sum(al, bl, &th, &tl);
    sl = sl + th;
    kd_fast_two_sum(sh, sl, &vh, &vl);
    vl = vl + tl;
    kd_fast_two_sum(vh, vl, hi, lo);
}

/* (hi, lo) = (ah, al) * (bh, bl): DWTimesDW (Joldes et al., Algorithm 12). */
KDRAY_HOT_INLINE void kd_ff_mul(kd_f32 ah, kd_f32 al, kd_f32 bh, kd_f32 bl, kd_f32* hi,
                                kd_f32* lo) {
    kd_f32 ch, cl;
    kd_two_product(ah, bh, &ch, &cl);
    const kd_f32 low = KDRAY_FMA(al, bh, KDRAY_FMA(ah, bl, al * bl));
    kd_fast_two_sum(ch, cl + low, hi, lo);
}

/* (hi, lo) = (ah, al) / (bh, bl): the float quotient, then one correction from the remainder
 * a - q b, computed in float-float (its leading part cancels, so it is nearly exact). */
KDRAY_HOT_INLINE void kd_ff_div(kd_f32 ah, kd_f32 al, kd_f32 bh, kd_f32 bl, kd_f32* hi,
                                kd_f32* lo) {
    const kd_f32 q = ah / bh;
    kd_f32 qbh, qbl, rh, rl;
    kd_ff_mul(q, 0.0f, bh, bl, &qbh, &qbl);
    kd_ff_add(ah, al, -qbh, -qbl, &rh, &rl);
    kd_fast_two_sum(q, (rh + rl) / bh, hi, lo);
}

/* a b - c d of four floats, rounded once to float (up to a near-tie of the exact value): both
 * products exactly, then their accurate difference. Zero exactly when a b = c d, and of the exact
 * value's sign otherwise, which is what the watertight test's edge fallback asks of it. */
KDRAY_HOT_INLINE kd_f32 kd_ff_diff_of_products(kd_f32 a, kd_f32 b, kd_f32 c, kd_f32 d) {
    kd_f32 ph, pl, qh, ql, hi, lo;
    kd_two_product(a, b, &ph, &pl);
    kd_two_product(c, d, &qh, &ql);
    kd_ff_add(ph, pl, -qh, -ql, &hi, &lo);
    return hi;
}

#endif /* KDRAY_KD_FLOAT_FLOAT_H */
