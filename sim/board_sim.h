/* SPDX-License-Identifier: MIT */
#ifndef GLINT_SIM_BOARD_SIM_H
#define GLINT_SIM_BOARD_SIM_H

/*
 * The simulated board: a backend of board/board.h ("sim"), registered by
 * the program (cmd/backends.c).  Its own rig-file keys (board.scenario,
 * board.log) and what it records are described in sim/board_sim.c.
 *
 * Errors: as board/board.h.  Threads: as board/board.h; the world it moves
 * is locked (sim/world.h).  Who frees: glint_board_close().
 */

#include "board/board.h"

extern const struct glint_board_ops glint_board_sim_ops;

#endif
