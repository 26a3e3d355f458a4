/* rk_common.c -- error buffer, tolerances and options defaults, reports (architect). */
#include "rk_fp.h" /* first: no contraction into multiply-adds (rk_fp.h) */
#include "rk_common.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static void format_into(char *buf, const char *fmt, va_list ap)
{
    int n = vsnprintf(buf, RK_MSG_LEN, fmt, ap);
    if (n < 0)
        buf[0] = '\0';
}

rk_status rk_fail(rk_error *err, rk_status status, const char *fmt, ...)
{
    if (err != NULL) {
        va_list ap;
        err->status = status;
        va_start(ap, fmt);
        format_into(err->message, fmt, ap);
        va_end(ap);
    }
    return status;
}

const char *rk_status_name(rk_status status)
{
    switch (status) {
    case RK_OK: return "ok";
    case RK_ERR_VALUE: return "value";
    case RK_ERR_WORK_LIMIT: return "work_limit";
    case RK_ERR_NONFINITE: return "nonfinite";
    case RK_ERR_SOLVER: return "solver";
    case RK_ERR_NOT_IMPLEMENTED: return "not_implemented";
    case RK_ERR_MEMORY: return "memory";
    case RK_ERR_INTERNAL: return "internal";
    }
    return "unknown";
}

const rk_tolerances RK_DEFAULT_TOLERANCES = {
    1e-9,   /* gap */
    1e-12,  /* step_gap */
    1e-3,   /* grazing */
    1e-10,  /* rest_velocity */
    1e-9,   /* step_rest_velocity */
    1e-10,  /* event */
    1e-3,   /* rise */
    1e-9,   /* clearly_open */
    0.1,    /* stateless_step */
    16,     /* sub_samples */
    1e-9,   /* lcp_exact */
    1e-12,  /* lcp_hint */
    1e-6    /* demand_floor */
};

rk_status rk_tolerances_check(const rk_tolerances *tol, rk_error *err)
{
    static const char *const names[] = {"gap", "step_gap", "grazing", "rest_velocity", "step_rest_velocity",
                                        "event", "rise", "clearly_open", "stateless_step", "lcp_exact",
                                        "lcp_hint", "demand_floor"};
    double values[12];
    int i;
    values[0] = tol->gap; values[1] = tol->step_gap; values[2] = tol->grazing;
    values[3] = tol->rest_velocity; values[4] = tol->step_rest_velocity; values[5] = tol->event;
    values[6] = tol->rise; values[7] = tol->clearly_open; values[8] = tol->stateless_step;
    values[9] = tol->lcp_exact; values[10] = tol->lcp_hint; values[11] = tol->demand_floor;
    for (i = 0; i < 12; i++) {
        if (!(isfinite(values[i]) && values[i] > 0.0 && values[i] < 1.0))
            return rk_fail(err, RK_ERR_VALUE, "tolerances.%s = %.17g is out of range; allowed range (0, 1)",
                           names[i], values[i]);
    }
    if (tol->sub_samples < 2 || tol->sub_samples > 1024)
        return rk_fail(err, RK_ERR_VALUE, "tolerances.sub_samples = %d is out of range; allowed range [2, 1024] "
                       "(an integer)", tol->sub_samples);
    return RK_OK;
}

void rk_options_default(rk_options *opt)
{
    opt->scheme = RK_SCHEME_EVENT_DRIVEN;
    opt->t0 = 0.0;
    opt->dt_max = 0.0;
    opt->tolerance = 1e-8;
    opt->theta = 0.5;
    opt->zeno_tol = 1e-6;
    opt->method = RK_METHOD_DOP853;
    opt->impact_log_size = 10000;
    opt->max_events = 100000;
    opt->tolerances = RK_DEFAULT_TOLERANCES;
}

void rk_report_add(rk_reports *reports, rk_report_kind kind, double t, const char *fmt, ...)
{
    if (reports->count < RK_MAX_REPORTS) {
        rk_report *r = &reports->items[reports->count];
        va_list ap;
        r->kind = kind;
        r->t = t;
        va_start(ap, fmt);
        format_into(r->message, fmt, ap);
        va_end(ap);
    }
    reports->count++;
}
