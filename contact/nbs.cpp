// contact/nbs.cpp: NBS detection (see nbs.hpp for the data layout and the algorithm).
#include "contact/nbs.hpp"

#include <algorithm>
#include <cmath>
#include <omp.h>

namespace fdem::contact {

namespace {

inline bool near_pair(const double* cx, const double* cy, const double* r, int i, int j, double buffer) {
    const double dx = cx[i] - cx[j], dy = cy[i] - cy[j];
    const double s = r[i] + r[j] + buffer;
    return dx * dx + dy * dy < s * s;
}

inline void emit(std::vector<int>& a, std::vector<int>& b, int ti, int tj) {
    a.push_back(ti < tj ? ti : tj);
    b.push_back(ti < tj ? tj : ti);
}

}  // namespace

void nbs_detect(const double* cx, const double* cy, const double* r, const int* id, int n, double buffer,
                CandidatePairs& out, NbsWorkspace& ws) {
    out.clear();
    if (n < 2) return;
    double r_max = 0.0, xmin = cx[0], xmax = cx[0], ymin = cy[0], ymax = cy[0];
    for (int i = 0; i < n; ++i) {
        r_max = std::max(r_max, r[i]);
        xmin = std::min(xmin, cx[i]);
        xmax = std::max(xmax, cx[i]);
        ymin = std::min(ymin, cy[i]);
        ymax = std::max(ymax, cy[i]);
    }
    // [MA98]: d = 2 (r_max + buffer) covers every pair distance r_i + r_j + buffer < d. A larger cell is still
    // correct (the stencil covers any distance < d), so widely scattered items enlarge d to keep the row and
    // column arrays O(n) instead of O(extent / d).
    double d = 2.0 * (r_max + buffer);
    const double cap = 4.0 * n + 64.0;
    d = std::max(d, std::max(xmax - xmin, ymax - ymin) / cap);
    if (!(d > 0.0)) d = 1.0;
    const int nx = static_cast<int>(std::floor((xmax - xmin) / d)) + 1;
    const int ny = static_cast<int>(std::floor((ymax - ymin) / d)) + 1;

    ws.ix.resize(n);
    ws.iy.resize(n);
    ws.row_next.resize(n);
    ws.row_head.assign(ny, -1);
    for (int i = 0; i < n; ++i) {
        ws.ix[i] = std::min(nx - 1, static_cast<int>((cx[i] - xmin) / d));
        ws.iy[i] = std::min(ny - 1, static_cast<int>((cy[i] - ymin) / d));
    }
    // Row lists built in reverse item order (push front); the order only has to be input-determined.
    for (int i = 0; i < n; ++i) {
        ws.row_next[i] = ws.row_head[ws.iy[i]];
        ws.row_head[ws.iy[i]] = i;
    }

    // Fixed chunks of rows: results do not depend on how many threads take the chunks.
    const int rows_per_chunk = std::max(1, ny / 64 + (ny % 64 != 0));
    const int n_chunks = (ny + rows_per_chunk - 1) / rows_per_chunk;
    ws.chunk_a.resize(n_chunks);
    ws.chunk_b.resize(n_chunks);
    const int n_threads = omp_get_max_threads();
    ws.col_cur.resize(n_threads);
    ws.col_below.resize(n_threads);
    ws.cell_next.resize(n_threads);

#pragma omp parallel if (n > 4096)
    {
        const int th = omp_get_thread_num();
        std::vector<int>& cur = ws.col_cur[th];
        std::vector<int>& below = ws.col_below[th];
        std::vector<int>& next = ws.cell_next[th];
        cur.assign(nx, -1);
        below.assign(nx, -1);
        next.resize(n);
        const int* ix = ws.ix.data();
        auto build = [&](std::vector<int>& heads, int row) {
            for (int i = ws.row_head[row]; i >= 0; i = ws.row_next[i]) {
                next[i] = heads[ix[i]];
                heads[ix[i]] = i;
            }
        };
        auto clear = [&](std::vector<int>& heads, int row) {
            for (int i = ws.row_head[row]; i >= 0; i = ws.row_next[i]) heads[ix[i]] = -1;
        };
#pragma omp for schedule(dynamic, 1)
        for (int c = 0; c < n_chunks; ++c) {
            std::vector<int>& oa = ws.chunk_a[c];
            std::vector<int>& ob = ws.chunk_b[c];
            oa.clear();
            ob.clear();
            const int row0 = c * rows_per_chunk, row1 = std::min(ny, row0 + rows_per_chunk);
            if (row0 > 0) build(below, row0 - 1);
            for (int row = row0; row < row1; ++row) {
                if (ws.row_head[row] >= 0) {
                    build(cur, row);
                    for (int i = ws.row_head[row]; i >= 0; i = ws.row_next[i]) {
                        const int cxi = ix[i];
                        // own cell: only items after i in the cell list, so each pair once
                        for (int j = next[i]; j >= 0; j = next[j])
                            if (near_pair(cx, cy, r, i, j, buffer)) emit(oa, ob, id[i], id[j]);
                        if (cxi > 0)
                            for (int j = cur[cxi - 1]; j >= 0; j = next[j])
                                if (near_pair(cx, cy, r, i, j, buffer)) emit(oa, ob, id[i], id[j]);
                        if (row > 0) {
                            const int c0 = std::max(0, cxi - 1), c1 = std::min(nx - 1, cxi + 1);
                            for (int cc = c0; cc <= c1; ++cc)
                                for (int j = below[cc]; j >= 0; j = next[j])
                                    if (near_pair(cx, cy, r, i, j, buffer)) emit(oa, ob, id[i], id[j]);
                        }
                    }
                }
                // slide the two-row window: the current row becomes the row below
                if (row > 0) clear(below, row - 1);
                std::swap(cur, below);
            }
            if (row1 - 1 >= 0) clear(below, row1 - 1);
        }
    }
    size_t total = 0;
    for (int c = 0; c < n_chunks; ++c) total += ws.chunk_a[c].size();
    out.a.reserve(total);
    out.b.reserve(total);
    for (int c = 0; c < n_chunks; ++c) {
        out.a.insert(out.a.end(), ws.chunk_a[c].begin(), ws.chunk_a[c].end());
        out.b.insert(out.b.end(), ws.chunk_b[c].begin(), ws.chunk_b[c].end());
    }
}

void brute_force_pairs(const double* cx, const double* cy, const double* r, const int* id, int n, double buffer,
                       CandidatePairs& out) {
    out.clear();
    std::vector<std::pair<int, int>> p;
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j)
            if (near_pair(cx, cy, r, i, j, buffer)) p.emplace_back(std::min(id[i], id[j]), std::max(id[i], id[j]));
    std::sort(p.begin(), p.end());
    for (const auto& q : p) {
        out.a.push_back(q.first);
        out.b.push_back(q.second);
    }
}

}  // namespace fdem::contact
