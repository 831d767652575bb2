// contact/nbs.hpp: NBS broad-phase contact detection ([MA98]; [M04] ch. 3; fdem/README.md 'Contact').
//
// DATA LAYOUT
//   Input : structure of arrays over the n "items" taking part (contact-capable triangles):
//           cx[n], cy[n] bounding-circle centres (m), r[n] radii (m), id[n] the triangle index of each item.
//   Output: two parallel int arrays a[P], b[P] of triangle indices with a < b, one entry per candidate pair.
//           Pairs come in row-major cell order (rows of increasing y, then the row's own list order); the order
//           depends only on the input, never on the thread count.
#pragma once

#include <vector>

namespace fdem::contact {

struct CandidatePairs {
    std::vector<int> a, b;  // triangle indices, a[p] < b[p]
    void clear() {
        a.clear();
        b.clear();
    }
    int size() const { return static_cast<int>(a.size()); }
};

// Reusable scratch so that repeated detections do not allocate (cold state; owned by the caller).
struct NbsWorkspace {
    std::vector<int> ix, iy, row_head, row_next;
    std::vector<std::vector<int>> chunk_a, chunk_b;
    std::vector<std::vector<int>> col_cur, col_below, cell_next;  // per thread
};

// Every pair of items with |c_i - c_j| < r_i + r_j + buffer (buffer in m), each pair once.
// Cells of size d = 2 (r_max + buffer) ([MA98]); singly linked lists per row and, row by row, per cell; each item
// meets only its own cell (items after it in the cell list), the cell to its left and the three cells of the
// row below: the 5-cell stencil that sees each neighbouring cell pair once. No sorting, no search; cost O(n)
// for any packing. Rows are processed in fixed chunks in parallel, results concatenated in chunk order.
void nbs_detect(const double* cx, const double* cy, const double* r, const int* id, int n, double buffer,
                CandidatePairs& out, NbsWorkspace& ws);

// The O(n^2) reference used by the tests: same criterion, pairs sorted by (a, b).
void brute_force_pairs(const double* cx, const double* cy, const double* r, const int* id, int n, double buffer,
                       CandidatePairs& out);

}  // namespace fdem::contact
