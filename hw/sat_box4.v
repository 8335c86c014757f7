// texsat reference datapath: the 4-read box sum at integer corners (Crow 1984, section 2.1).
//
//   sum = S(x1, y1) - S(x0, y1) - S(x1, y0) + S(x0, y0)
//
// over the box [x0, x1) x [y0, y1), 0 <= x0 <= x1 <= TEX_W, 0 <= y0 <= y1 <= TEX_H, on texsat's
// flat table (see sat_reader.vh). Exact: the table is monotone, every partial result lies in
// [0, total], so W_E bits (the width the crate's width proof gives the table) hold everything
// and the adder is W_E bits wide.
//
// One memory port; 2 cycles per read (issue, capture), corners on the zero row or column are
// not read. `reads` counts the reads issued: it must equal the golden vectors' count.
`timescale 1ns / 1ps
module sat_box4 #(
    parameter TEX_W = 64,
    parameter TEX_H = 64,
    parameter W_E = 32,     // table entry bits (the width proof's entry width)
    parameter W_IDX = 16,   // bits of a corner coordinate (0 ..= TEX_W)
    parameter W_ADDR = 24
) (
    input  wire              clk,
    input  wire              rst,
    input  wire              start,
    input  wire [W_IDX-1:0]  x0,
    input  wire [W_IDX-1:0]  y0,
    input  wire [W_IDX-1:0]  x1,
    input  wire [W_IDX-1:0]  y1,
    output wire              rd_en,
    output wire [W_ADDR-1:0] rd_addr,
    input  wire [W_E-1:0]    rd_data,
    output reg               done,
    output reg  [W_E-1:0]    sum,
    output reg  [3:0]        reads
);
`include "sat_reader.vh"

    localparam IDLE = 2'd0, ISSUE = 2'd1, CAPTURE = 2'd2;
    reg [1:0] state;
    reg [2:0] k;                 // corner 0..3: (x1,y1) +, (x0,y1) -, (x1,y0) -, (x0,y0) +
    reg [W_IDX-1:0] bx0, by0, bx1, by1;
    reg [W_E-1:0] acc;
    reg zero;                    // the current corner is on the zero row or column

    wire [W_IDX-1:0] cx = (k == 0 || k == 2) ? bx1 : bx0;
    wire [W_IDX-1:0] cy = (k == 0 || k == 1) ? by1 : by0;

    // The read port, driven in ISSUE: the memory registers the address at the clock edge that
    // ends ISSUE, and its data is captured at the edge that ends CAPTURE.
    assign rd_en = (state == ISSUE) && (cx != 0) && (cy != 0);
    assign rd_addr = corner_addr(cx, cy);

    always @(posedge clk) begin
        if (rst) begin
            state <= IDLE;
            done <= 1'b0;
        end else begin
            done <= 1'b0;
            case (state)
                IDLE: if (start) begin
                    bx0 <= x0; by0 <= y0; bx1 <= x1; by1 <= y1;
                    k <= 0;
                    acc <= 0;
                    reads <= 0;
                    if (x0 == x1 || y0 == y1) begin
                        // A zero-area box sums to 0 with no read (as texsat's lookups do).
                        sum <= 0;
                        done <= 1'b1;
                    end else
                        state <= ISSUE;
                end
                ISSUE: begin
                    zero <= (cx == 0) || (cy == 0);
                    if (rd_en)
                        reads <= reads + 1;
                    state <= CAPTURE;
                end
                CAPTURE: begin
                    // The signs of Crow's formula; modulo 2^W_E the result is exact (it lies in
                    // [0, total] and total < 2^W_E).
                    if (!zero)
                        acc <= (k == 0 || k == 3) ? acc + rd_data : acc - rd_data;
                    if (k == 3) begin
                        state <= IDLE;
                        done <= 1'b1;
                        sum <= zero ? acc : acc + rd_data;
                    end else begin
                        k <= k + 1;
                        state <= ISSUE;
                    end
                end
                default: state <= IDLE;
            endcase
        end
    end
endmodule
