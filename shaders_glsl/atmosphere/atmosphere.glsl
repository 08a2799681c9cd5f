// The atmosphere effect (effects/atmosphere): exponential height fog with
// single scattering, in closed form along the view ray; the CPU twin is
// src/reference/atmosphere.rs. `fog` is (sigma0, 1 / H, z_low, g); `haze`
// holds a colour in xyz, `zenith` one in xyz and the clear air's optical
// depth straight up in w.
#ifndef VISTA_ATMOSPHERE_GLSL
#define VISTA_ATMOSPHERE_GLSL

// Optical depth from the eye `a` to `b` (world metres).
float fog_optical_depth(vec4 fog, vec3 a, vec3 b) {
    float d = length(b - a);
    float x = (b.z - a.z) * fog.y;
    // (1 - e^-x) / x, its series near 0 (no 0 / 0 on level rays).
    float shape = abs(x) < 1.0e-4 ? 1.0 - 0.5 * x : (1.0 - exp(-x)) / x;
    return fog.x * exp(-(a.z - fog.z) * fog.y) * d * shape;
}

// Light the haze scatters towards the eye along the unit view direction.
vec3 fog_inscatter(vec4 fog, vec3 haze, vec3 view_dir, vec3 sun_dir, vec3 sun, vec3 sky) {
    float g = fog.w;
    float mu = dot(view_dir, sun_dir);
    float phase = (1.0 - g * g) / pow(1.0 + g * g - 2.0 * g * mu, 1.5);
    return haze * (sky + sun * phase);
}

// How much of the zenith colour comes through the haze above the eye and
// the clear air (optical depth `air` straight up) along `view_dir`.
float fog_sky_transmittance(vec4 fog, float air, vec3 eye, vec3 view_dir) {
    if (view_dir.z <= 1.0e-6) {
        return 0.0;
    }
    float sigma = fog.x * exp(-(eye.z - fog.z) * fog.y);
    return exp(-(sigma / fog.y + air) / view_dir.z);
}

#endif
