/*
 * test_crba.c - the oracle's composite-rigid-body mass matrix (src/reference/crba.c) against the
 * closed-form double pendulum, against columns of recursive Newton-Euler, against the mass matrix
 * that the world-frame kinetic energy gives by polarisation, for symmetry and positive
 * definiteness, and against merged bodies for fixed joints.
 */
#include <criterion/criterion.h>
#include <math.h>

#include "model_fixture.h"
#include "oracle.h"
#include "oracle_fixture.h"

static double mm_a[FX_MAX_NV * FX_MAX_NV], mm_b[FX_MAX_NV * FX_MAX_NV];

Test(crba, matches_lagrangian_double_pendulum)
{
    const double mass[2] = {1.3, 0.7}, len[2] = {1.1, 0.8};
    ctc_model *m;
    ctc_oracle *o = fx_make_rods(2, mass, len, &m);
    fx_rng rng = {13};

    for (int s = 0; s < 100; s++) {
        /* q as for two joints of any type: fx_random_state's spherical branch writes four, and gcc
           -O3 warns about it though the pendulum's joints are revolute */
        double q[8], v[2], a[2], tau[2], want[4], got[4];
        fx_random_state(&rng, m, q, v, a);
        fx_double_pendulum(mass, len, q, v, a, want, tau);
        ctc_oracle_mass_matrix(m, o, q, got);
        cr_assert_leq(fx_max_abs_diff(4, got, want), 1e-14 * fx_max_abs(4, want),
                      "sample %d: M = (%.17g %.17g; %.17g %.17g), Lagrangian (%.17g %.17g; "
                      "%.17g %.17g)",
                      s, got[0], got[1], got[2], got[3], want[0], want[1], want[2], want[3]);
    }
    fx_release(m, o);
}

Test(crba, matches_rnea_columns_on_random_spatial_chains)
{
    /* column i of M = RNEA(q, v, e_i) - RNEA(q, v, 0) */
    const int sizes[] = {1, 2, 3, 7, 16, 64};
    fx_rng rng = {8};
    double worst = 0.0;

    for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++) {
        for (int seed = 0; seed < 3; seed++) {
            ctc_model *m;
            ctc_oracle *o = fx_make_random(&rng, sizes[si], CTC_FORM_SPATIAL, &m);
            int nv = m->nv;
            double q[FX_MAX_NQ], v[FX_MAX_NV], e[FX_MAX_NV] = {0};
            double bias[FX_MAX_NV], col[FX_MAX_NV];

            fx_random_state(&rng, m, q, v, NULL);
            ctc_oracle_mass_matrix(m, o, q, mm_a);
            ctc_oracle_rnea(m, o, q, v, e, bias);
            double scale = fmax(1.0, fmax(fx_max_abs(nv * nv, mm_a), fx_max_abs(nv, bias)));
            for (int i = 0; i < nv; i++) {
                e[i] = 1.0;
                ctc_oracle_rnea(m, o, q, v, e, col);
                e[i] = 0.0;
                for (int r = 0; r < nv; r++) {
                    double err = fabs(mm_a[(size_t)r * nv + i] - (col[r] - bias[r])) / scale;
                    worst = fmax(worst, err);
                    cr_assert_leq(err, 1e-12, "n = %d: M[%d][%d] = %.17g, RNEA column %.17g",
                                  sizes[si], r, i, mm_a[(size_t)r * nv + i], col[r] - bias[r]);
                }
            }
            fx_release(m, o);
        }
    }
    cr_log_info("crba vs rnea columns: worst relative error %.2e (tolerance 1e-12)", worst);
}

Test(crba, mass_matrix_is_symmetric_positive_definite)
{
    const int sizes[] = {1, 2, 3, 7, 16, 64};
    fx_rng rng = {21};

    for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++) {
        for (int seed = 0; seed < 5; seed++) {
            ctc_model *m;
            ctc_oracle *o = fx_make_random(&rng, sizes[si], CTC_FORM_SPATIAL, &m);
            int nv = m->nv;
            double q[FX_MAX_NQ];

            fx_random_state(&rng, m, q, NULL, NULL);
            ctc_oracle_mass_matrix(m, o, q, mm_a);
            for (int i = 0; i < nv; i++) {
                for (int j = 0; j < i; j++) {
                    cr_assert_eq(mm_a[(size_t)i * nv + j], mm_a[(size_t)j * nv + i],
                                 "n = %d: M[%d][%d] != M[%d][%d]", sizes[si], i, j, j, i);
                }
            }
            cr_assert(fx_cholesky(nv, mm_a), "n = %d, seed %d: M is not positive definite",
                      sizes[si], seed);
            fx_release(m, o);
        }
    }
}

Test(crba, kinetic_energy_matches_world_frame_body_sum)
{
    /* 1/2 v^T M v = sum_k 1/2 m_k |v_ck|^2 + 1/2 w_k^T I_k w_k from world-frame kinematics */
    const int sizes[] = {1, 2, 3, 7, 16, 64};
    fx_rng rng = {34};
    double worst = 0.0;

    for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++) {
        for (int seed = 0; seed < 5; seed++) {
            ctc_model *m;
            ctc_oracle *o = fx_make_random(&rng, sizes[si], CTC_FORM_SPATIAL, &m);
            int nv = m->nv;
            double q[FX_MAX_NQ], v[FX_MAX_NV];

            fx_random_state(&rng, m, q, v, NULL);
            ctc_oracle_mass_matrix(m, o, q, mm_a);
            double quad = 0.0;
            for (int i = 0; i < nv; i++) {
                for (int j = 0; j < nv; j++) {
                    quad += v[i] * mm_a[(size_t)i * nv + j] * v[j];
                }
            }
            double want = fx_kinetic_energy(m, q, v);
            double err = fabs(0.5 * quad - want) / want;
            worst = fmax(worst, err);
            cr_assert_leq(err, 1e-12, "n = %d, seed %d: 1/2 v'Mv = %.17g, body sum %.17g",
                          sizes[si], seed, 0.5 * quad, want);
            fx_release(m, o);
        }
    }
    cr_log_info("crba kinetic energy: worst relative error %.2e (tolerance 1e-12)", worst);
}

Test(crba, matches_energy_polarisation_on_random_spatial_chains)
{
    /* every entry of M against M_ij = T(e_i + e_j) - T(e_i) - T(e_j), M_ii = 2 T(e_i) */
    const int sizes[] = {1, 2, 3, 7, 16};
    fx_rng rng = {55};
    double worst = 0.0;

    for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++) {
        for (int seed = 0; seed < 3; seed++) {
            ctc_model *m;
            ctc_oracle *o = fx_make_random(&rng, sizes[si], CTC_FORM_SPATIAL, &m);
            int nv = m->nv;
            double q[FX_MAX_NQ];

            fx_random_state(&rng, m, q, NULL, NULL);
            ctc_oracle_mass_matrix(m, o, q, mm_a);
            fx_energy_mass_matrix(m, q, mm_b);
            double err = fx_max_abs_diff(nv * nv, mm_a, mm_b) / fx_max_abs(nv * nv, mm_b);
            worst = fmax(worst, err);
            cr_assert_leq(err, 1e-12, "n = %d, seed %d: relative error %.3e", sizes[si], seed, err);
            fx_release(m, o);
        }
    }
    cr_log_info("crba vs energy polarisation: worst relative error %.2e (tolerance 1e-12)", worst);
}

Test(crba, fixed_joint_equals_merged_body)
{
    fx_rng rng = {79};
    double worst = 0.0;

    for (int w = 0; w < 5; w++) {
        ctc_model *mf, *mm;
        ctc_oracle *of, *om;
        fx_make_fixed_merged(&rng, 5, w, &mf, &of, &mm, &om);
        int nv = mf->nv;
        double q[FX_MAX_NQ];

        fx_random_state(&rng, mf, q, NULL, NULL);
        ctc_oracle_mass_matrix(mf, of, q, mm_a);
        ctc_oracle_mass_matrix(mm, om, q, mm_b);
        double err = fx_max_abs_diff(nv * nv, mm_a, mm_b) / fx_max_abs(nv * nv, mm_b);
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-12, "fixed joint %d: relative difference %.3e", w, err);
        fx_release(mf, of);
        fx_release(mm, om);
    }
    cr_log_info("crba fixed vs merged: worst relative difference %.2e (tolerance 1e-12)", worst);
}

Test(crba, walks_the_parents_on_a_branched_tree)
{
    /* on a Y tree made by hand from a chain's model (two rods hung from one), CRBA's fill walks
       j = lambda(j) up the tree: M matches the closed form of two double pendulums sharing
       joint 0, and the two branches' joints do not couple, M_12 = M_21 = 0 exactly */
    const double mass[3] = {1.3, 0.7, 0.9}, len[3] = {1.1, 0.8, 0.6};
    ctc_model *m;
    ctc_oracle *o = fx_make_y_tree(mass, len, &m);
    fx_rng rng = {23};
    double worst = 0.0;

    for (int s = 0; s < 200; s++) {
        double q[12], mm[9], want[9], tau[3];
        const double zero[3] = {0.0, 0.0, 0.0};
        fx_random_state(&rng, m, q, NULL, NULL);
        fx_y_tree(mass, len, q, zero, zero, want, tau);
        ctc_oracle_mass_matrix(m, o, q, mm);
        cr_assert_eq(mm[5], 0.0, "sample %d: M_12 = %.17g", s, mm[5]);
        cr_assert_eq(mm[7], 0.0, "sample %d: M_21 = %.17g", s, mm[7]);
        double err = fx_rel_diff(9, mm, want);
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-13, "sample %d: M differs from the closed form by %.2e", s, err);
    }
    cr_log_info("crba Y tree: worst relative error %.2e (tolerance 1e-13)", worst);
    fx_release(m, o);
}
