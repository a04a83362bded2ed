/* Balance-heuristic MIS weight of strategy (s, t) by the ratio recursion of seed ch. 5
 * (pbrt-v3 MISWeight; Veach 10.2): with p_i the density of generating the same path with i
 * light vertices,
 *     w_s = 1 / sum_i (p_i / p_s),
 * and each ratio p_{i+1}/p_i needs only the forward and reverse densities of one vertex, so no
 * product of densities is ever formed (a path's density can under- or overflow float at scene
 * scales of 1e-4 or 1e4; ratios of neighbouring densities do not).
 *
 * The connection changes four densities (and may replace an endpoint with a freshly sampled
 * vertex); pbrt assigns them in place for the duration of the call (ScopedAssignment). Here the
 * endpoints are private copies and the four reverse densities are held in locals, so the
 * subpaths themselves are never modified. */
#ifndef CLBDPT_MIS_H
#define CLBDPT_MIS_H

#include "strategies.h"
#include "vertex.h"

/* One factor p_rev / p_fwd of the ratio recursion. A density of 0 is a convention where a
 * delta lobe or a delta light sampled the vertex: it stands for a delta factor that the two
 * strategies of the ratio share, so it counts as 1 (seed 5.4.2, remap0); the strategies that
 * would have to connect through the delta are excluded by the delta tests. Any other 0 is a
 * real density: a reverse density of 0 means this strategy, and every one further along on
 * the same side (their densities contain the same factor), cannot produce the path (a
 * direction pair across a shading normal's terminator band: bsdf_pdf is 0 both ways), so the
 * side's sum ends there (returns 0). A forward density of 0 that is no convention means the
 * strategy that made the path could not have made it (float rounding on a grazing direction):
 * the ratio is taken as 0 as well, which keeps the weight finite. */
inline float mis_ratio(float pdf_rev, int rev_is_delta, float pdf_fwd, int fwd_is_delta) {
    if (pdf_rev == 0.0f && rev_is_delta) pdf_rev = 1.0f;
    if (pdf_fwd == 0.0f && fwd_is_delta) pdf_fwd = 1.0f;
    return pdf_rev > 0.0f && pdf_fwd > 0.0f ? pdf_rev / pdf_fwd : 0.0f;
}

/* The ratio recursion's tails, summed once per subpath (bdpt only). Away from the connection
 * the recursion's factors are the subpath's own: for a camera subpath, the terms of strategies
 * (s + t - i, i) with i <= t - 3 are
 *     r_{t-2} * sum_{i <= t-3} g_i * prod_{j = i .. t-3} ratio_j,
 * with ratio_j from vertex j's stored densities and delta flags and g_i the term's sample count
 * (0 where a delta vertex excludes it), and the sum is the same for every connection whose
 * camera end lies past vertex t - 3. So it is stored there, in mis_tail, by the recursion
 *     tail_k = ratio_k * (g_k + tail_{k-1}),
 * and mis_weight walks only the two vertices next to the connection (whose densities the
 * connection changes) and adds r_{t-2} times the tail: O(1) per connection instead of O(s + t),
 * which counts where paths are long (bdpt of the Cornell box at max depth 20: 1.18x the
 * samples/s without Russian roulette, 1.10x with it; cornell-fog 1.07x; at the other bundled
 * scenes' depths about 1.0x).
 * The sums are the loop's up to float rounding (images differ in the last bits).
 * A tail's strategies have at least three vertices on the other side of the connection, so g_i
 * takes one of few values: on the camera side the light subpath's sample count for t = 1
 * (i = 1) and for the inner connections (i >= 2, if the mix makes them); on the light side 1 for
 * s = 0, the light samples' selection ratio for s = 1 (NEE_OWN_SELECTION, see mis_weight), and
 * the inner connections' count. A ratio of 0 ends the recursion's sum (mis_ratio), so it resets
 * the tail to 0; so does a tail with no term yet (an infinite ratio must not make it NaN). */
inline void mis_fill_camera_tails(const StrategyMix* mix, PathVertex* path, int n) {
#if STRATEGIES_READ_SUBPATH_PDF_REV
    float inner = mix->inner_connections ? mix->light_subpaths : 0.0f;
    float tail = 0.0f;
    for (int k = 1; k + 1 < n; ++k) {
        float ratio = mis_ratio(path[k].pdf_rev, path[k + 1].delta, path[k].pdf_fwd, path[k - 1].delta);
        float count = k == 1 ? mix->light_subpaths : inner;
        float term = !path[k].delta && !path[k - 1].delta ? count : 0.0f;
        tail = ratio > 0.0f && term + tail > 0.0f ? ratio * (term + tail) : 0.0f;
        path[k].mis_tail = tail;
    }
#endif
}

/* The ratio by which light samples (NEE_OWN_SELECTION) take the light of a light subpath of n
 * vertices, from its second vertex, over select_pdf (light_sample_selection_ratio): the s = 1
 * term's scale in every connection with s >= 2 of that subpath, so computed once per subpath.
 * 1 where light samples choose by select_pdf or the subpath has no second vertex. */
inline float light_subpath_s1_scale(const SceneData* scene, const PathVertex* path, int n) {
#if defined(NEE_OWN_SELECTION)
    if (n >= 2) return light_sample_selection_ratio(scene, path[0].light, path[1].p);
#endif
    return 1.0f;
}

inline void mis_fill_light_tails(const SceneData* scene, const StrategyMix* mix, PathVertex* path, int n,
                                 float s1_scale) {
#if STRATEGIES_READ_SUBPATH_PDF_REV
    float inner = mix->inner_connections ? mix->light_subpaths : 0.0f;
    float tail = 0.0f;
    for (int k = 0; k + 1 < n; ++k) {
        int delta_light_vertex = k > 0 ? path[k - 1].delta : vertex_is_delta_light(scene, &path[0]);
        int rev_is_delta = path[k + 1].delta || (k == 0 && delta_light_vertex);
        float ratio = mis_ratio(path[k].pdf_rev, rev_is_delta, path[k].pdf_fwd, delta_light_vertex);
        float count = k == 0 ? 1.0f : (k == 1 ? s1_scale : inner);
        float term = !path[k].delta && !delta_light_vertex ? count : 0.0f;
        tail = ratio > 0.0f && term + tail > 0.0f ? ratio * (term + tail) : 0.0f;
        path[k].mis_tail = tail;
    }
#endif
}

/* mix: the strategies in use and their sample counts (cl/strategies.h).
 * sampled: the vertex the connection sampled afresh (camera vertex for t = 1, light vertex for
 * s = 1), ignored otherwise.
 * to_qs, to_pt: with media, the distance-sampling densities of the connecting segment toward
 * its light-side and camera-side ends (cl/medium.h; 1 in vacuum, ignored for s = 0).
 * light_s1_scale: light_subpath_s1_scale of the light subpath (read for s >= 2 only).
 * outer_share: null, or where to store the sum of the weights of the mix's outer strategies
 * (s <= 1 or t = 1, those of a mix without inner connections) for the same path: the share
 * of it that such a mix would take on (host/render/strategy_pilot.h, subset moments). It
 * needs each strategy's term, so the subpaths' tails are not used. */
inline float mis_weight_and_outer_share(const SceneData* scene, const StrategyMix* mix,
                                        const PathVertex* light_path, const PathVertex* camera_path,
                                        const PathVertex* sampled, int s, int t, float to_qs, float to_pt,
                                        float light_s1_scale, float* outer_share) {
    /* The connection's endpoints: t = 1 replaces the camera vertex and (otherwise) s = 1 the
     * light vertex with the freshly sampled one; the subpath arrays are not read there (a path
     * tracer has no light subpath at all). */
    const PathVertex* pt = t == 1 ? sampled : (t > 0 ? &camera_path[t - 1] : 0);
    const PathVertex* qs = s == 1 && t != 1 ? sampled : (s > 0 ? &light_path[s - 1] : 0);
    const PathVertex* qs_minus = s > 1 ? &light_path[s - 2] : 0;
    const PathVertex* pt_minus = t > 1 ? &camera_path[t - 2] : 0;

    /* Whether the path's emitter is an area light, for strategy_enabled's (1,1) rule. */
    const PathVertex* emitter = s == 0 ? pt : (s == 1 ? qs : &light_path[0]);
    int light_is_area = emitter->type == VERTEX_SURFACE || vertex_light_kind(scene, emitter) == LIGHT_AREA;

    /* A light sample (s = 1, t >= 2) takes its light with a probability of its own where
     * NEE_OWN_SELECTION (cl/lights.h), every other strategy with select_pdf. The densities below
     * use select_pdf throughout; the s = 1 term is then scaled by the ratio of the two, and if
     * s = 1 is the strategy weighed, every other term is divided by it. */
    float s1_scale = 1.0f;
#if defined(NEE_OWN_SELECTION) && INTEGRATOR != INTEGRATOR_LT /* a light tracer has no s = 1, t >= 2 */
    if (s + t >= 3) {
        /* the vertex a light sample would be taken from: the path's second from the light */
        if (s >= 2)
            s1_scale = light_s1_scale;
        else
            s1_scale = light_sample_selection_ratio(scene, emitter->light, (s == 0 ? pt_minus : pt)->p);
    }
#endif

    /* The endpoints are connected deterministically, so neither is a delta vertex of this
     * path; their reverse densities and those of their predecessors follow the connection.
     * Only those that the recursions below reach are evaluated: the recursions stop where the
     * integrator's strategies end (a path tracer's never pass pt, a light tracer's never enter
     * the light side). */
    int camera_steps = min(t - 1, STRATEGY_MAX_LIGHT_VERTICES - s);
    int light_steps = min(s, STRATEGY_MAX_CAMERA_VERTICES - t);
    float pt_pdf_rev = 0.0f, pt_minus_pdf_rev = 0.0f, qs_pdf_rev = 0.0f, qs_minus_pdf_rev = 0.0f;
    /* Where both densities at an endpoint are needed (toward the other endpoint and toward its
     * own predecessor), they come from one evaluation of its BSDF (vertex_pdfs_between). */
    if (camera_steps >= 1 && light_steps >= 2)
        vertex_pdfs_between(scene, qs, qs_minus, pt, &pt_pdf_rev, &qs_minus_pdf_rev);
    else if (camera_steps >= 1)
        pt_pdf_rev = s > 0 ? vertex_pdf(scene, qs, qs_minus, pt) : vertex_pdf_light_origin(scene, pt, pt_minus);
    else if (light_steps >= 2)
        qs_minus_pdf_rev = vertex_pdf(scene, qs, pt, qs_minus);
    if (camera_steps >= 2 && light_steps >= 1 && s > 0)
        vertex_pdfs_between(scene, pt, qs, pt_minus, &pt_minus_pdf_rev, &qs_pdf_rev);
    else {
        if (camera_steps >= 2)
            pt_minus_pdf_rev = s > 0 ? vertex_pdf(scene, pt, qs, pt_minus) : vertex_pdf_light(scene, pt, pt_minus);
        if (light_steps >= 1) qs_pdf_rev = vertex_pdf(scene, pt, pt_minus, qs);
    }
#ifdef HAS_MEDIA
    /* A density toward a vertex through a medium includes the segment's distance sampling: the
     * connection's own for the endpoints, the subpath's stored one for their predecessors. */
    if (s > 0) pt_pdf_rev *= to_pt;
    qs_pdf_rev *= to_qs;
    if (pt_minus) pt_minus_pdf_rev *= pt->dist_rev;
    if (qs_minus) qs_minus_pdf_rev *= qs->dist_rev;
#endif

    /* With sample counts n_i (cl/strategies.h) each term is n_i p_i / (n_s p_s). */
    float inv_count = 1.0f / strategy_sample_count(mix, s, t);
    float sum_ri = 0.0f, sum_outer = 0.0f;
    /* Camera side: r_i for strategies (s + t - i, i), i = t-1 .. 1. Vertex i's reverse density
     * is a convention when vertex i+1 is a delta vertex of the subpath (the connection's pt is
     * not), its forward density when vertex i-1 is. */
    float ri = 1.0f;
    for (int i = t - 1; i >= t - camera_steps; --i) {
#if STRATEGIES_READ_SUBPATH_PDF_REV
        if (i <= t - 3 && !outer_share) { /* the subpath's own tail (mis_fill_camera_tails); ri is r_{t-2} */
            if (camera_path[i].mis_tail > 0.0f) sum_ri += ri * camera_path[i].mis_tail * inv_count;
            break;
        }
#endif
        float pdf_rev = i == t - 1 ? pt_pdf_rev : (i == t - 2 ? pt_minus_pdf_rev : camera_path[i].pdf_rev);
        float pdf_fwd = i == t - 1 ? pt->pdf_fwd : camera_path[i].pdf_fwd;
        int delta = i == t - 1 ? 0 : camera_path[i].delta;
        int rev_is_delta = i + 1 < t - 1 && camera_path[i + 1].delta;
        ri *= mis_ratio(pdf_rev, rev_is_delta, pdf_fwd, camera_path[i - 1].delta);
        if (ri == 0.0f) break;
        if (!delta && !camera_path[i - 1].delta && strategy_enabled(mix, s + t - i, i, light_is_area)) {
            float term = ri * strategy_sample_count(mix, s + t - i, i) * inv_count;
            if (s + t - i == 1 && i >= 2) term *= s1_scale;
            sum_ri += term;
            if (s + t - i <= 1 || i == 1) sum_outer += term;
        }
    }
    /* Light side: r_i for strategies (i, s + t - i), i = s-1 .. 0, with the same conventions;
     * the light vertex's own densities are conventions for a delta light as well (a point's
     * position, a direction's direction). */
    ri = 1.0f;
    for (int i = s - 1; i >= s - light_steps; --i) {
#if STRATEGIES_READ_SUBPATH_PDF_REV
        if (i <= s - 3 && !outer_share) { /* the subpath's own tail (mis_fill_light_tails) */
            if (light_path[i].mis_tail > 0.0f) sum_ri += ri * light_path[i].mis_tail * inv_count;
            break;
        }
#endif
        float pdf_rev = i == s - 1 ? qs_pdf_rev : (i == s - 2 ? qs_minus_pdf_rev : light_path[i].pdf_rev);
        float pdf_fwd = i == s - 1 ? qs->pdf_fwd : light_path[i].pdf_fwd;
        int delta = i == s - 1 ? 0 : light_path[i].delta;
        int delta_light_vertex = i > 0 ? light_path[i - 1].delta
                                       : vertex_is_delta_light(scene, s == 1 ? qs : &light_path[0]);
        int rev_is_delta = (i + 1 < s - 1 && light_path[i + 1].delta) || (i == 0 && delta_light_vertex);
        ri *= mis_ratio(pdf_rev, rev_is_delta, pdf_fwd, delta_light_vertex);
        if (ri == 0.0f) break;
        if (!delta && !delta_light_vertex && strategy_enabled(mix, i, s + t - i, light_is_area)) {
            float term = ri * strategy_sample_count(mix, i, s + t - i) * inv_count;
            if (i == 1 && s + t - 1 >= 2) term *= s1_scale;
            sum_ri += term;
            if (i <= 1) sum_outer += term;
        }
    }
    if (s == 1 && t >= 2) {
        sum_ri /= s1_scale;
        sum_outer /= s1_scale;
    }
    if (outer_share) *outer_share = ((s <= 1 || t == 1 ? 1.0f : 0.0f) + sum_outer) / (1.0f + sum_ri);
    return 1.0f / (1.0f + sum_ri);
}

inline float mis_weight(const SceneData* scene, const StrategyMix* mix, const PathVertex* light_path,
                        const PathVertex* camera_path, const PathVertex* sampled, int s, int t, float to_qs,
                        float to_pt) {
    return mis_weight_and_outer_share(scene, mix, light_path, camera_path, sampled, s, t, to_qs, to_pt,
                                      light_subpath_s1_scale(scene, light_path, s), 0);
}

#endif
