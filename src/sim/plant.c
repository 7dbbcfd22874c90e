/*
 * plant.c - the joint forces of a controlled coordinate (plant.h): viscous friction, regularised
 * Coulomb friction and a linear spring, and the sensors' noise generator, written as plant.h
 * states them.
 */
#include "plant.h"

#include <math.h>

double ctc_plant_joint_force(const ctc_plant_coord *p, double q, double v)
{
    double tau = -p->viscous * v - p->spring * (q - p->spring_rest);
    if (p->coulomb > 0) tau -= p->coulomb * tanh(v / p->coulomb_velocity);
    return tau;
}

int ctc_plant_has_sensor_error(const ctc_plant_coord *p)
{
    return p->noise_q != 0 || p->noise_v != 0 || p->resolution != 0;
}

/* splitmix64's next output; the uniform in [0, 1) of its top 53 bits */
static double uniform(unsigned long long *state)
{
    unsigned long long z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1p-53;
}

double ctc_plant_normal(unsigned long long *state)
{
    const double two_pi = 6.283185307179586476925286766559;
    double ua = uniform(state), ub = uniform(state);
    return sqrt(-2 * log(1 - ua)) * cos(two_pi * ub);
}

int ctc_plant_has_joint_force(const ctc_plant_coord *p)
{
    return p->viscous != 0 || p->coulomb != 0 || p->spring != 0;
}
