/* walk.c: closes the loop around the LDCBF footstep controller from C.
 *
 * A humanoid modelled as a linear inverted pendulum (LIP) walks from rest at
 * the origin to the goal (10, 10) m among the six obstacles of the paper's
 * scenario. The controller runs at 20 Hz (8 cycles per 0.4 s step); between
 * cycles the LIP is integrated in closed form (ldcbf_lip_propagate, the
 * controller's own model); at each step end the swing foot lands on the last
 * commanded target and the last commanded turning rate takes effect. This is
 * the loop of the Rust fixture `ldcbf_nav::fixtures::walk`, cycle for cycle.
 *
 *   walk          one line per step, then whether the goal was reached
 *   walk --hex    one line per control cycle with every input and output
 *                 number as the hex bits of the double (for the bit-for-bit
 *                 comparison with the Rust controller: ffi/tests/walk_c.rs)
 *
 * Build (see ffi/README.md): compile with -ffp-contract=off (or -std=c11) so
 * that the compiler does not fuse a*b+c into one rounding: the loop's own
 * arithmetic must round as Rust's does for the bit-for-bit check.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ldcbf.h"

/* The controller lives here: no allocation. */
static _Alignas(LDCBF_CONTROLLER_ALIGN) unsigned char storage[LDCBF_CONTROLLER_SIZE];

/* The paper's obstacles: each is the convex hull of its points (m, world),
 * all points one after the other, and the number of points of each. */
static const double points[] = {
    2.0, 7.5, 1.5, 7.0, 1.8, 6.5,                               /* 0 */
    4.0, 6.5, 4.3, 6.8, 4.7, 6.5, 4.5, 6.2, 4.1, 6.2,           /* 1 */
    7.0, 7.0, 7.5, 7.5, 8.0, 7.0, 7.5, 6.5,                     /* 2 */
    6.0, 2.5, 6.5, 2.0, 7.0, 2.5,                               /* 3 */
    1.5, 3.0, 1.8, 3.3, 2.2, 3.0, 2.0, 2.6, 1.6, 2.6,           /* 4 */
    2.5, 3.5, 2.8, 3.8, 3.2, 3.5, 3.0, 3.1, 2.6, 3.1,           /* 5 */
};
static const uint32_t counts[] = {3, 5, 4, 3, 5, 5};
#define N_OBSTACLES ((uint32_t)(sizeof counts / sizeof counts[0]))

#define MAX_STEPS 150
#define CYCLES_PER_STEP 8

/* The bits of a double, for exact printing. */
static uint64_t bits(double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static void hex(double x) { printf(" %016" PRIx64, bits(x)); }

/* Prints a failed call with the controller's own description, returns 1. */
static int fail(const LdcbfController *ctl, const char *what, LdcbfResult r) {
    char msg[160];
    msg[0] = '\0';
    if (ctl != NULL) {
        ldcbf_last_error(ctl, msg, sizeof msg);
    }
    fprintf(stderr, "walk: %s failed: %s (%s)\n", what, ldcbf_result_name(r), msg);
    return 1;
}

static void print_cycle_hex(unsigned i, const LdcbfInput *in, const LdcbfOutput *out) {
    printf("cycle %u", i);
    hex(in->com_position[0]);
    hex(in->com_position[1]);
    hex(in->com_velocity[0]);
    hex(in->com_velocity[1]);
    hex(in->heading);
    hex(in->turning_rate);
    hex(in->stance_foot[0]);
    hex(in->stance_foot[1]);
    printf(" %" PRIu32, in->stance_side);
    hex(in->time_in_step);
    printf(" |");
    hex(out->foot_target[0]);
    hex(out->foot_target[1]);
    hex(out->turning_rate);
    printf(" %s %" PRIu32 " %" PRIu32 " %" PRIu32, ldcbf_cycle_status_name(out->status),
           out->info.source, out->info.qp_status, out->info.iterations);
    for (int k = 0; k < LDCBF_HORIZON; k++) {
        hex(out->plan.feet[k][0]);
        hex(out->plan.feet[k][1]);
        hex(out->plan.states[k].position[0]);
        hex(out->plan.states[k].position[1]);
        hex(out->plan.states[k].velocity[0]);
        hex(out->plan.states[k].velocity[1]);
        hex(out->plan.states[k].heading);
    }
    hex(out->info.cost);
    hex(out->info.max_violation);
    hex(out->info.min_h0);
    printf(" %" PRIu32 " %" PRIu32 "\n", out->info.active_set_size, out->info.active_obstacles);
}

int main(int argc, char **argv) {
    int hex_mode = argc > 1 && strcmp(argv[1], "--hex") == 0;
    if (argc > 2 || (argc == 2 && !hex_mode)) {
        fprintf(stderr, "usage: %s [--hex]\n", argv[0]);
        return 2;
    }
    if (ldcbf_api_version() != LDCBF_API_VERSION) {
        fprintf(stderr, "walk: header (API %d) and library (API %" PRIu32 ") differ\n",
                LDCBF_API_VERSION, ldcbf_api_version());
        return 1;
    }

    LdcbfController *ctl = NULL;
    LdcbfResult r = ldcbf_init(storage, sizeof storage, &ctl);
    if (r != LDCBF_RESULT_OK) {
        return fail(NULL, "ldcbf_init", r);
    }
    LdcbfConfig cfg;
    ldcbf_config_default(&cfg); /* the paper's Table I, a point robot */
    r = ldcbf_configure(ctl, &cfg);
    if (r != LDCBF_RESULT_OK) {
        return fail(ctl, "ldcbf_configure", r);
    }

    const double goal[2] = {10.0, 10.0};
    const double dt = cfg.step_duration / CYCLES_PER_STEP;
    /* At rest at the origin, heading 0, left stance foot under the CoM. */
    LdcbfInput in = {
        .com_position = {0.0, 0.0},
        .com_velocity = {0.0, 0.0},
        .heading = 0.0,
        .turning_rate = 0.0,
        .stance_foot = {0.0, 0.0},
        .stance_side = LDCBF_SIDE_LEFT,
        .time_in_step = 0.0,
        .goal = {goal[0], goal[1]},
    };
    LdcbfOutput out;
    unsigned steps = 0, cycle = 0, not_optimal = 0;
    int reached = 0;
    for (cycle = 0; cycle < CYCLES_PER_STEP * MAX_STEPS; cycle++) {
        r = ldcbf_step(ctl, &in, points, counts, N_OBSTACLES, &out);
        if (r != LDCBF_RESULT_OK) {
            return fail(ctl, "ldcbf_step", r);
        }
        if (out.status != LDCBF_CYCLE_STATUS_OPTIMAL) {
            not_optimal++;
        }
        if (hex_mode) {
            print_cycle_hex(cycle, &in, &out);
        }
        /* The plant: the LIP over one cycle about the stance foot. */
        double p[2], v[2];
        r = ldcbf_lip_propagate(ctl, in.com_position, in.com_velocity, in.stance_foot, dt, p, v);
        if (r != LDCBF_RESULT_OK) {
            return fail(ctl, "ldcbf_lip_propagate", r);
        }
        memcpy(in.com_position, p, sizeof p);
        memcpy(in.com_velocity, v, sizeof v);
        in.heading += in.turning_rate * dt;
        in.time_in_step += dt;
        if (in.time_in_step >= cfg.step_duration - 1e-9) {
            /* Step end: the swing foot lands on the commanded target. */
            in.time_in_step = 0.0;
            in.stance_foot[0] = out.foot_target[0];
            in.stance_foot[1] = out.foot_target[1];
            in.stance_side = in.stance_side == LDCBF_SIDE_LEFT ? LDCBF_SIDE_RIGHT : LDCBF_SIDE_LEFT;
            in.turning_rate = out.turning_rate;
            steps++;
            if (!hex_mode) {
                printf("step %3u: foot (%7.3f, %7.3f) m, heading %6.3f rad, %s\n", steps,
                       in.stance_foot[0], in.stance_foot[1], in.heading,
                       ldcbf_cycle_status_name(out.status));
            }
        }
        double dx = in.com_position[0] - goal[0], dy = in.com_position[1] - goal[1];
        if (sqrt(dx * dx + dy * dy) < 0.15) {
            reached = 1;
            cycle++;
            break;
        }
    }
    if (hex_mode) {
        printf("done %u\n", cycle);
    } else {
        printf("%s after %u steps (%u control cycles, %u not optimal)\n",
               reached ? "goal reached" : "goal NOT reached", steps, cycle, not_optimal);
    }
    return reached ? 0 : 1;
}
