// Shared by the lookup datapaths: the corner read sequence of a flat summed-area table held in
// a synchronous single-port memory (`rd_en`/`rd_addr` in one cycle, `rd_data` the next).
//
// The table is texsat's flat layout: entry (i, j) at address j * TEX_W + i holds
// S(i + 1, j + 1) = the sum of texels (i', j') with i' <= i, j' <= j. The corner function
// S(X, Y) is therefore the entry at (Y - 1) * TEX_W + (X - 1), and S(0, Y) = S(X, 0) = 0: those
// corners are not read (as the crate does; its cost counters count no read for them).
//
// Included inside a module that declares TEX_W, W_ADDR and W_IDX.

// Address of S(X, Y) for 1 <= X <= TEX_W, 1 <= Y <= TEX_H.
function [W_ADDR-1:0] corner_addr;
    input [W_IDX-1:0] X;
    input [W_IDX-1:0] Y;
    begin
        corner_addr = (Y - 1) * TEX_W + (X - 1);
    end
endfunction
