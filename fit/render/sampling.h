/* SPDX-License-Identifier: MIT */
#ifndef GLINT_FIT_RENDER_SAMPLING_H
#define GLINT_FIT_RENDER_SAMPLING_H

/*
 * Deterministic sample sequences: the same inputs give the same numbers.
 *
 * Errors: none (inline arithmetic).  Threads: re-entrant.  Who frees:
 * nothing.
 */

#include <stdint.h>

/* A well-mixed 32-bit hash (lowbias32 by C. Wellons). */
static inline uint32_t glint_hash32(uint32_t x)
{
	x ^= x >> 16;
	x *= 0x7feb352dU;
	x ^= x >> 15;
	x *= 0x846ca68bU;
	x ^= x >> 16;
	return x;
}

static inline uint32_t glint_hash3(uint32_t a, uint32_t b, uint32_t c)
{
	return glint_hash32(a ^ glint_hash32(b ^ glint_hash32(c)));
}

/* Uniform in [0, 1) from a hash. */
static inline double glint_u01(uint32_t h)
{
	return (h >> 8) * (1.0 / 16777216.0);
}

/* Van der Corput radical inverse in base 2. */
static inline double glint_radical2(uint32_t i)
{
	i = (i << 16) | (i >> 16);
	i = ((i & 0x00ff00ffU) << 8) | ((i & 0xff00ff00U) >> 8);
	i = ((i & 0x0f0f0f0fU) << 4) | ((i & 0xf0f0f0f0U) >> 4);
	i = ((i & 0x33333333U) << 2) | ((i & 0xccccccccU) >> 2);
	i = ((i & 0x55555555U) << 1) | ((i & 0xaaaaaaaaU) >> 1);
	return i * (1.0 / 4294967296.0);
}

/*
 * Point i of the 2-D Sobol (0, 2)-sequence (van der Corput; the Pascal
 * matrix mod 2), digitally shifted (xor) by the two words of seed's
 * hashes.  Every block of 2^m points from a multiple of 2^m is a
 * (0, m, 2)-net, and the xor keeps it one: the pixel's hits take
 * consecutive blocks, each its own stratified set, together a larger
 * one.
 */
static inline void glint_sobol2_bits(uint32_t i, uint32_t bits[2])
{
	uint32_t b = 0, v = 1U << 31;

	for (uint32_t k = i; k; k >>= 1, v ^= v >> 1)
		if (k & 1)
			b ^= v;
	bits[0] = (uint32_t)(glint_radical2(i) * 4294967296.0);
	bits[1] = b;
}

/* The digital shift of seed (glint_sobol2()): xor it with the bits. */
static inline void glint_sobol2_shift(uint32_t seed, uint32_t shift[2])
{
	shift[0] = glint_hash32(seed ^ 0x68e31da4U);
	shift[1] = glint_hash32(seed ^ 0xb5297a4dU);
}

static inline void glint_sobol2(uint32_t i, uint32_t seed, double u[2])
{
	uint32_t bits[2], shift[2];

	glint_sobol2_bits(i, bits);
	glint_sobol2_shift(seed, shift);
	u[0] = (bits[0] ^ shift[0]) * (1.0 / 4294967296.0);
	u[1] = (bits[1] ^ shift[1]) * (1.0 / 4294967296.0);
}

/*
 * Element i of a pseudo-random permutation of [0, n), one per seed: a
 * bijection of the next power of two (xor-shifts, odd multipliers and
 * seeded additions, each invertible modulo 2^b), walked until it lands
 * below n.  Pairs the points of two stratified sets without the
 * correlation of pairing them by index.
 */
static inline uint32_t glint_permute(uint32_t i, uint32_t n, uint32_t seed)
{
	uint32_t mask = n - 1, shift;

	mask |= mask >> 1;
	mask |= mask >> 2;
	mask |= mask >> 4;
	mask |= mask >> 8;
	mask |= mask >> 16;
	shift = 1;
	while ((mask >> shift) > 1 && shift < 4)
		shift++;
	do {
		i ^= seed;
		i = (i * 0xe170893dU) & mask;
		i ^= (i & mask) >> shift;
		i = (i + (seed >> 16)) & mask;
		i = (i * 0x0929eb3fU) & mask;
		i ^= (i & mask) >> (shift + 1);
		i = (i * 0x6935fa69U) & mask;
		i ^= (seed >> 8) & mask;
		i = (i * 0x74dcb303U) & mask;
	} while (i >= n);
	return i;
}

/*
 * Point k of n of a 2-D Hammersley set, toroidally shifted by a per-sequence
 * random offset (Cranley-Patterson rotation) seeded by `seed`.
 */
static inline void glint_hammersley(uint32_t k, uint32_t n, uint32_t seed,
				    double u[2])
{
	double a = (k + 0.5) / n + glint_u01(glint_hash32(seed));
	double b =
		glint_radical2(k) + glint_u01(glint_hash32(seed ^ 0x9e3779b9U));
	u[0] = a - (int)a;
	u[1] = b - (int)b;
}

#endif
