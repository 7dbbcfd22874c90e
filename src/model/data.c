/*
 * data.c - allocation of the per-simulation state (data.h): every array sized once from the model,
 * and the thread setting of its GDCA passes; with merged bodies (model.h), the reduced model's
 * data beside it, and the hand-over of settings and results between the two.
 */
#include "data.h"

#include <stdlib.h>
#include <string.h>

ctc_data *ctc_data_new(const ctc_model *m)
{
    ctc_data *d = calloc(1, sizeof *d);
    if (d == NULL) return NULL;
    size_t n = (size_t)m->nbodies, dim = (size_t)m->dim;
    size_t nt = n > 1 ? n - 1 : 1, nj = (size_t)m->njoints;
    size_t nfwd = m->chain ? nt : 2 * n; /* a tree's sequential order: S_k and R_k per body */
    d->dim = m->dim;
    d->hsize = (int)(3 * dim * dim + 2 * dim);
    d->singular_joint = -1;
    d->threads = 1;
    d->opt = ctc_options_default();

    d->xpos = calloc(n * 3, sizeof(double));
    d->xrot = calloc(n * 9, sizeof(double));
    d->xcom = calloc(n * 3, sizeof(double));
    d->omega = calloc(n * 3, sizeof(double));
    d->xvel = calloc(n * 3, sizeof(double));
    d->xangle = calloc(n, sizeof(double));
    d->jnt_P = calloc(nj * 3 * dim, sizeof(double));
    d->jnt_D = calloc(nj * dim * dim, sizeof(double));
    d->jnt_beta = calloc(nj * dim, sizeof(double));
    d->hr = calloc(n * 6, sizeof(double));
    d->hbody = calloc(n * (size_t)d->hsize, sizeof(double));
    d->hfwd = calloc(nfwd * (size_t)d->hsize, sizeof(double));
    d->hinv = calloc(nt * (size_t)d->hsize, sizeof(double));
    d->fwd_E = calloc(n * dim * dim, sizeof(double));
    d->fwd_z = calloc(n * dim, sizeof(double));
    d->fwd_res = calloc(4 * (size_t)m->nvx + 1, sizeof(double));
    d->fwd_load_prev = calloc(nj * dim, sizeof(double));
    d->inv_E = calloc(n * dim * dim, sizeof(double));
    d->inv_z = calloc(n * dim, sizeof(double));
    d->csize = (int)(dim * dim + 2 * dim + 3);
    d->icomp = calloc((2 * n - 1) * (size_t)d->csize, sizeof(double));
    d->icomp_e = calloc(n * dim, sizeof(double));
    d->tload = calloc((2 * n - 1) * 2 * dim, sizeof(double));
    d->rake = calloc(n * (dim * dim + dim), sizeof(double));
    d->jnt_load = calloc(nj * dim, sizeof(double));
    d->jnt_load_inv = calloc(nj * dim, sizeof(double));
    d->loop_cond = 1;
    d->handles_stamp = 1; /* icomp_stamp = hbias_stamp = 0: no records yet */
    d->xbuf = calloc(2 * (size_t)m->nvx + (size_t)m->nq + 1, sizeof(double));
    if (d->xpos == NULL || d->xrot == NULL || d->xcom == NULL || d->omega == NULL ||
        d->xvel == NULL || d->jnt_P == NULL || d->jnt_D == NULL || d->jnt_beta == NULL ||
        d->hr == NULL || d->rake == NULL || d->hbody == NULL || d->hfwd == NULL ||
        d->hinv == NULL || d->fwd_E == NULL || d->fwd_z == NULL || d->fwd_res == NULL ||
        d->fwd_load_prev == NULL || d->inv_E == NULL || d->inv_z == NULL || d->icomp == NULL ||
        d->icomp_e == NULL || d->tload == NULL || d->jnt_load == NULL || d->jnt_load_inv == NULL ||
        d->xbuf == NULL || d->xangle == NULL) {
        ctc_data_free(d);
        return NULL;
    }
    if (m->dyn != NULL && (d->dyn = ctc_data_new(m->dyn)) == NULL) {
        ctc_data_free(d);
        return NULL;
    }
    return d;
}

ctc_data *ctc_data_dyn_begin(const ctc_model *m, ctc_data *d)
{
    (void)m;
    ctc_data *e = d->dyn;
    e->opt = d->opt;
    e->baumgarte[0] = d->baumgarte[0], e->baumgarte[1] = d->baumgarte[1];
    e->pool_owner = d->pool_owner != NULL ? d->pool_owner : d;
    e->eval_of = &d->eval;
    return e;
}

/* the loads of joints (njoints x dim) of m from those of m->dyn */
static void dyn_loads(const ctc_model *m, const double *from, double *to)
{
    const ctc_model *r = m->dyn;
    const size_t dim = (size_t)m->dim;
    memset(to, 0, (size_t)m->njoints * dim * sizeof *to);
    for (int j = 0; j < r->nbodies; j++) {
        memcpy(to + dim * (size_t)m->dyn_body[j], from + dim * (size_t)j, dim * sizeof *to);
    }
    if (m->has_loop) {
        memcpy(to + dim * (size_t)m->nbodies, from + dim * (size_t)r->nbodies, dim * sizeof *to);
    }
}

void ctc_data_dyn_end(const ctc_model *m, ctc_data *d)
{
    const ctc_data *e = d->dyn;
    const int sj = e->singular_joint;
    dyn_loads(m, e->jnt_load, d->jnt_load);
    dyn_loads(m, e->jnt_load_inv, d->jnt_load_inv);
    d->singular_joint = sj < 0 ? -1 : sj < m->dyn->nbodies ? m->dyn_body[sj] : m->nbodies;
    d->loop_cond = e->loop_cond;
    d->fwd_refine_done = e->fwd_refine_done;
    d->fwd_refine_undone = e->fwd_refine_undone;
    d->fwd_split = e->fwd_split;
}

void ctc_data_free(ctc_data *d)
{
    if (d == NULL) return;
    ctc_data_free(d->dyn);
    ctc_pool_free(d->pool);
    free(d->xpos);
    free(d->xrot);
    free(d->xcom);
    free(d->omega);
    free(d->xvel);
    free(d->xangle);
    free(d->jnt_P);
    free(d->jnt_D);
    free(d->jnt_beta);
    free(d->hr);
    free(d->hbody);
    free(d->hfwd);
    free(d->hinv);
    free(d->fwd_E);
    free(d->fwd_z);
    free(d->fwd_res);
    free(d->fwd_load_prev);
    free(d->inv_E);
    free(d->inv_z);
    free(d->icomp);
    free(d->icomp_e);
    free(d->tload);
    free(d->rake);
    free(d->jnt_load);
    free(d->jnt_load_inv);
    free(d->xbuf);
    free(d);
}

ctc_status ctc_data_set_threads(ctc_data *d, int nthreads, char *err, size_t errlen)
{
    if (nthreads < 1 || nthreads > CTC_MAX_THREADS) {
        return ctc_fail(CTC_EINVAL, err, errlen, "threads must be 1 to %d (got %d)",
                        CTC_MAX_THREADS, nthreads);
    }
    if (nthreads != d->threads) {
        ctc_pool_free(d->pool);
        d->pool = NULL;
        d->pool_failed = 0;
        d->threads = nthreads;
        d->eval = (ctc_eval_gate){0};
    }
    return CTC_OK;
}

void ctc_data_share_pool(ctc_data *d, ctc_data *owner)
{
    d->pool_owner = owner == d ? NULL : owner;
    d->eval = (ctc_eval_gate){0};
}

void ctc_data_eval_begin(ctc_data *d)
{
    const ctc_data *o = d->pool_owner != NULL ? d->pool_owner : d;
    if (o->threads < 2) return;
    ctc_eval_gate *e = &d->eval;
    if (e->open && e->gated) ctc_pool_gate_record(&e->gate, e->split, e->t1 - e->t0);
    e->open = 1;
    e->gated = 0;
    e->split = ctc_pool_gate_way(&e->gate);
    e->t0 = ctc_pool_clock();
}

int ctc_data_eval_split(ctc_data *d)
{
    if (d->opt.par_split || d->opt.par_grain > 0) return 1;
    ctc_eval_gate *e = d->eval_of != NULL ? d->eval_of : &d->eval;
    if (!e->open) return ctc_pool_gate_way(&e->gate);
    e->gated = 1;
    return e->split;
}

void ctc_data_eval_pass_done(ctc_data *d)
{
    ctc_eval_gate *e = d->eval_of != NULL ? d->eval_of : &d->eval;
    if (e->gated) e->t1 = ctc_pool_clock();
}
