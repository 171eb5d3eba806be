/* SPDX-License-Identifier: MIT */
/*
 * The fit methods by name: one file each (method_*.c) behind struct
 * fit_method (fit/internal.h).
 */
#include "fit/internal.h"

static const struct fit_method *const methods[] = {
	[GLINT_FIT_THREE_PASS] = &fit_method_three_pass,
	[GLINT_FIT_NAIVE] = &fit_method_naive,
	[GLINT_FIT_VARPRO] = &fit_method_varpro,
};

const struct fit_method *fit_method_of(const struct glint_fit_opts *o)
{
	if (o->optimizer == GLINT_OPT_ANNEAL)
		return &fit_method_anneal;
	if ((unsigned)o->method >= sizeof(methods) / sizeof(methods[0]))
		return NULL;
	return methods[o->method];
}

const struct fit_method *fit_method_named(enum glint_fit_method m)
{
	return methods[m];
}
