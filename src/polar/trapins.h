/* trapins: the randomized insertion's work on the trapezoid slots
 * (trapmap.c), compiled there twice: with the slots as btrap records and
 * with the slots packed in bits (the packed build), SLOTFN naming each
 * copy's functions, TG / TS reading and writing a slot's field by name
 * and TGN / TSN its neighbour link k (see tget, tset in polar_int.h), so
 * that neither copy tests the layout in its hot loops. No include guard:
 * it is meant to be included twice. */

static uint32_t SLOTFN(new_trap)(dbuild *b)
{
    uint32_t t;
    if (b->nfree > 0) {
        t = b->freel;
        b->freel = TGN(b, t, 0);
        b->nfree--;
    } else {
        if (b->ntrap >= b->tcap && !grow_traps(b)) {
            b->fail = 1;
            return 0;
        }
        t = b->ntrap++;
    }
    TSN(b, t, 0, POLAR_NONE);
    TSN(b, t, 1, POLAR_NONE);
    TSN(b, t, 2, POLAR_NONE);
    TSN(b, t, 3, POLAR_NONE);
    TS(b, t, leaf, POLAR_NONE);
    return t;
}

/* Frame coordinates of the right axis point of trapezoid t. */
static vec2 SLOTFN(trc)(const dbuild *b, uint32_t t)
{
    return fpt(b->pd, b->frame, TG(b, t, rp));
}

/* Gives slot t back (its leaf already POLAR_NONE). */
static void SLOTFN(free_trap)(dbuild *b, uint32_t t)
{
    TSN(b, t, 0, b->freel);
    b->freel = t;
    b->nfree++;
}

/* Replaces the neighbour link 'old' of trapezoid x on side f. */
static void SLOTFN(relink)(dbuild *b, uint32_t x, int f, uint32_t old, uint32_t nw)
{
    if (x != POLAR_NONE && TGN(b, x, f) == old)
        TSN(b, x, f, nw);
}

static void SLOTFN(set_trap)(dbuild *b, uint32_t t, uint32_t lp, uint32_t rp, uint32_t top, uint32_t bot)
{
    TS(b, t, lp, lp);
    TS(b, t, rp, rp);
    TS(b, t, top, top);
    TS(b, t, bot, bot);
}

/* Records trapezoid t (just made, its sides final) in the roles it holds. */
static void SLOTFN(note_trap)(dbuild *b, uint32_t t)
{
    uint32_t lp = TG(b, t, lp), rp = TG(b, t, rp);
    sroles *top = &b->SR[TG(b, t, top)], *bot = &b->SR[TG(b, t, bot)];
    b->PR[lp].side[0] = t;
    b->PR[rp].side[1] = t;
    if (top->end[0] == lp)
        top->down[0] = t;
    if (top->end[1] == rp)
        top->down[1] = t;
    if (bot->end[0] == lp)
        bot->up[0] = t;
    if (bot->end[1] == rp)
        bot->up[1] = t;
}

/* The trapezoid holding the points just right of end point p of the new
 * piece (p = its left end, towards D = its right end Q) or just left of it
 * (right end, towards D = P), p being in the map already: from one
 * trapezoid whose axis on that side is p's, up or down across the pieces
 * ending at p (the trapezoids by role), in O(1) per piece at p; at most
 * WALK_MAX of them, else (or on anything unexpected) POLAR_NONE and the
 * DAG is searched instead. */
static uint32_t SLOTFN(walk_at)(dbuild *b, uint32_t p, vec2 D, int right)
{
    int k = right ? 0 : 1;
    uint32_t t = b->PR[p].side[k], n;
    for (n = 0; n < WALK_MAX && t != POLAR_NONE; n++) {
        uint32_t e = (right ? TG(b, t, lp) : TG(b, t, rp)), xt, xb;
        int o;
        if (TG(b, t, leaf) == POLAR_NONE || e != p)
            return POLAR_NONE;
        b->steps++;
        xt = TG(b, t, top);
        xb = TG(b, t, bot);
        if (b->SR[xt].end[k] == p) {
            o = geom_orient(pend(b->pd, b->frame, b->SR, xt, 0),
                             pend(b->pd, b->frame, b->SR, xt, 1), D);
            if (o == 0)
                return POLAR_NONE;    /* overlapping pieces: the DAG says so */
            if (o > 0) {
                t = b->SR[xt].up[k];
                continue;
            }
        }
        if (b->SR[xb].end[k] == p) {
            o = geom_orient(pend(b->pd, b->frame, b->SR, xb, 0),
                             pend(b->pd, b->frame, b->SR, xb, 1), D);
            if (o == 0)
                return POLAR_NONE;
            if (o < 0) {
                t = b->SR[xb].down[k];
                continue;
            }
        }
        return t;
    }
    return POLAR_NONE;
}

/* Follows the new piece leftwards from the trapezoid t holding its right
 * end r; returns k, the trapezoids crossed being list[0..k], left first. */
static uint32_t SLOTFN(follow_back)(dbuild *b, uint32_t t, vec2 P, vec2 Q)
{
    uint32_t k = 0, i;
    b->list[0] = t;
    while (lex_cmp(P, bpt(b, TG(b, t, lp))) < 0) {
        int o = geom_orient(P, Q, bpt(b, TG(b, t, lp)));
        uint32_t nx = o > 0 ? TGN(b, t, LL) : TGN(b, t, UL);
        /* the neighbour must be live and share the axis: the walk moves
         * strictly leftwards, whatever the input */
        if (o == 0 || nx == POLAR_NONE || k + 1 >= b->lcap || TG(b, nx, leaf) == POLAR_NONE ||
            TG(b, nx, rp) != TG(b, t, lp)) {
            b->fail = 2;
            return k;
        }
        b->list[++k] = t = nx;
    }
    for (i = 0; i < k - i; i++) {
        uint32_t x = b->list[i];
        b->list[i] = b->list[k - i];
        b->list[k - i] = x;
    }
    return k;
}

/* Follows the new piece (ends l < r) through the map; returns k, the
 * trapezoids crossed being list[0..k]. The search starts at the x node of
 * l, or of r when only r is in the map (then the piece is followed
 * leftwards), or at the root. */
static uint32_t SLOTFN(follow)(dbuild *b, uint32_t l, uint32_t r)
{
    vec2 P = b->P, Q = b->Q;
    uint32_t k = 0;
    if (b->hint[l] == POLAR_NONE && b->hint[r] != POLAR_NONE) {
        uint32_t t = SLOTFN(walk_at)(b, r, P, 0);
        if (t == POLAR_NONE)
            t = find_last(b, b->hint[r], Q, P);
        return b->fail ? 0 : SLOTFN(follow_back)(b, t, P, Q);
    }
    b->list[0] = b->hint[l] != POLAR_NONE ? SLOTFN(walk_at)(b, l, Q, 1) : POLAR_NONE;
    if (b->list[0] == POLAR_NONE)
        b->list[0] = find_first(b, b->hint[l] != POLAR_NONE ? b->hint[l] : 0, P, Q);
    if (b->fail)
        return 0;
    for (;;) {
        uint32_t t = b->list[k], nx;
        vec2 rc = SLOTFN(trc)(b, t);
        int o;
        if (lex_cmp(Q, rc) <= 0)
            break;
        o = geom_orient(P, Q, rc);
        nx = o > 0 ? TGN(b, t, LR) : TGN(b, t, UR);
        if (o == 0 || nx == POLAR_NONE || k + 1 >= b->lcap || TG(b, nx, leaf) == POLAR_NONE ||
            TG(b, nx, lp) != TG(b, t, rp)) {
            b->fail = 2;
            return k;
        }
        b->list[++k] = nx;
    }
    return k;
}

/* Builds the chain of new trapezoids above (up = 1) or below the piece. */
static void SLOTFN(make_chain)(dbuild *b, uint32_t s, uint32_t l, uint32_t r, uint32_t k, int up)
{
    vec2 P = b->P, Q = b->Q;
    uint32_t *part = up ? b->up : b->lo;
    uint32_t j, cur = SLOTFN(new_trap)(b);
    int fo = up ? UL : LL, fc = up ? UR : LR;     /* outer-side links */
    if (b->fail)
        return;
    if (up)
        SLOTFN(set_trap)(b, cur, l, r, TG(b, b->list[0], top), s);
    else
        SLOTFN(set_trap)(b, cur, l, r, s, TG(b, b->list[0], bot));
    part[0] = cur;
    for (j = 0; j < k; j++) {
        uint32_t t = b->list[j], t1 = b->list[j + 1], R = TG(b, t, rp), nx, x;
        int o = geom_orient(P, Q, SLOTFN(trc)(b, t));
        if ((o > 0) != (up != 0)) {
            part[j + 1] = cur;        /* the axis at R is cut away: merge */
            continue;
        }
        TS(b, cur, rp, R);
        nx = SLOTFN(new_trap)(b);
        if (b->fail)
            return;
        if (up)
            SLOTFN(set_trap)(b, nx, R, r, TG(b, t1, top), s);
        else
            SLOTFN(set_trap)(b, nx, R, r, s, TG(b, t1, bot));
        x = TGN(b, t, fc);
        TSN(b, cur, fc, x);
        SLOTFN(relink)(b, x, fo, t, cur);
        TSN(b, cur, up ? LR : UR, nx);
        TSN(b, nx, up ? LL : UL, cur);
        x = TGN(b, t1, fo);
        TSN(b, nx, fo, x);
        SLOTFN(relink)(b, x, fc, t1, nx);
        cur = nx;
        part[j + 1] = cur;
    }
}

/* Links the new trapezoids at one end of the inserted piece: E (the old
 * first / last crossed trapezoid) had neighbours enb on that side; X is
 * the new trapezoid beyond the end or POLAR_NONE; U, L the new parts above
 * and below at that end. left: the left end. */
static void SLOTFN(link_end)(dbuild *b, int left, uint32_t E, const uint32_t *enb, uint32_t X,
                     uint32_t U, uint32_t L)
{
    int ou = left ? UL : UR, ol = left ? LL : LR;     /* outer sides */
    int iu = left ? UR : UL, il = left ? LR : LL;     /* their far sides */
    if (X != POLAR_NONE) {
        TSN(b, X, ou, enb[ou]);
        TSN(b, X, ol, enb[ol]);
        SLOTFN(relink)(b, enb[ou], iu, E, X);
        SLOTFN(relink)(b, enb[ou], il, E, X);
        SLOTFN(relink)(b, enb[ol], iu, E, X);
        SLOTFN(relink)(b, enb[ol], il, E, X);
        TSN(b, X, iu, U);
        TSN(b, X, il, L);
        TSN(b, U, ou, X);
        TSN(b, L, ol, X);
    } else {
        TSN(b, U, ou, enb[ou]);
        TSN(b, L, ol, enb[ol]);
        SLOTFN(relink)(b, enb[ou], iu, E, U);
        SLOTFN(relink)(b, enb[ou], il, E, L);
        SLOTFN(relink)(b, enb[ol], iu, E, U);
        SLOTFN(relink)(b, enb[ol], il, E, L);
    }
}

static void SLOTFN(leaf_of)(dbuild *b, uint32_t t)
{
    if (t != POLAR_NONE && TG(b, t, leaf) == POLAR_NONE)
        TS(b, t, leaf, new_node(b, N_LEAF, t, 0, 0));
}

/* The old leaf n of crossed trapezoid j becomes the search for its parts:
 * x tests at new ends (A left, B right), then the y test of s. */
static void SLOTFN(replace_leaf)(dbuild *b, uint32_t s, uint32_t l, uint32_t r, uint32_t n, uint32_t j,
                         uint32_t A, uint32_t B)
{
    uint32_t y0 = TG(b, b->lo[j], leaf), y1 = TG(b, b->up[j], leaf), inner, xq;
    uint32_t ky = ykind(b, s);
    if (A == POLAR_NONE && B == POLAR_NONE) {
        nset(b, n, PACK(ky, s), y0, y1);
        return;
    }
    inner = new_node(b, ky, s, y0, y1);
    if (A != POLAR_NONE) {
        xq = B != POLAR_NONE ? new_node(b, N_X, r, inner, TG(b, B, leaf)) : inner;
        if (b->fail)
            return;
        nset(b, n, PACK(N_X, l), TG(b, A, leaf), xq);
        b->hint[l] = n;
        if (B != POLAR_NONE)
            b->hint[r] = xq;
    } else if (!b->fail) {
        nset(b, n, PACK(N_X, r), inner, TG(b, B, leaf));
        b->hint[r] = n;
    }
}

/* Inserts wall piece s (raw ends rl < rr in the frame). */
static void SLOTFN(insert_seg)(dbuild *b, const irec *in)
{
    uint32_t s = in->s, l = in->l, r = in->r, k, j, first, last;
    uint32_t A = POLAR_NONE, B = POLAR_NONE, fnb[4], lnb[4];
    b->P = in->P;
    b->Q = in->Q;
    k = SLOTFN(follow)(b, l, r);
    if (b->fail)
        return;
    b->steps += k + 1;
    first = b->list[0];
    last = b->list[k];
    for (j = 0; j < 4; j++) {
        fnb[j] = TGN(b, first, j);
        lnb[j] = TGN(b, last, j);
    }
    /* the first trapezoid holds l (its left axis at or before l), the
     * last r: A, B are needed unless those axes are l's and r's own
     * (canonical indices: one index per position) */
    if (l != TG(b, first, lp)) {
        A = SLOTFN(new_trap)(b);
        if (!b->fail)
            SLOTFN(set_trap)(b, A, TG(b, first, lp), l, TG(b, first, top), TG(b, first, bot));
    }
    if (!b->fail && r != TG(b, last, rp)) {
        B = SLOTFN(new_trap)(b);
        if (!b->fail)
            SLOTFN(set_trap)(b, B, r, TG(b, last, rp), TG(b, last, top), TG(b, last, bot));
    }
    if (!b->fail)
        SLOTFN(make_chain)(b, s, l, r, k, 1);
    if (!b->fail)
        SLOTFN(make_chain)(b, s, l, r, k, 0);
    if (b->fail)
        return;
    SLOTFN(link_end)(b, 1, first, fnb, A, b->up[0], b->lo[0]);
    SLOTFN(link_end)(b, 0, last, lnb, B, b->up[k], b->lo[k]);
    SLOTFN(leaf_of)(b, A);
    SLOTFN(leaf_of)(b, B);
    for (j = 0; j <= k; j++) {
        SLOTFN(leaf_of)(b, b->up[j]);
        SLOTFN(leaf_of)(b, b->lo[j]);
    }
    for (j = 0; j <= k && !b->fail; j++) {
        uint32_t t = b->list[j];
        SLOTFN(replace_leaf)(b, s, l, r, TG(b, t, leaf), j, j == 0 ? A : POLAR_NONE,
                     j == k ? B : POLAR_NONE);
        TS(b, t, leaf, POLAR_NONE);
        SLOTFN(free_trap)(b, t);
    }
    if (A != POLAR_NONE)
        SLOTFN(note_trap)(b, A);
    if (B != POLAR_NONE)
        SLOTFN(note_trap)(b, B);
    for (j = 0; j <= k; j++) {
        if (j == 0 || b->up[j] != b->up[j - 1])
            SLOTFN(note_trap)(b, b->up[j]);
        if (j == 0 || b->lo[j] != b->lo[j - 1])
            SLOTFN(note_trap)(b, b->lo[j]);
    }
}

/* The first trapezoid (the Bounds box) and the insertion of every piece
 * in order (polar_dag_build). */
static void SLOTFN(insert_all)(dbuild *b, const polar_map *m, uint32_t nw)
{
    uint32_t i, t = SLOTFN(new_trap)(b);
    if (b->fail)
        return;
    SLOTFN(set_trap)(b, t, m->box_lo, m->box_hi, m->box_top, m->box_bot);
    TS(b, t, leaf, new_node(b, N_LEAF, t, 0, 0));
    SLOTFN(note_trap)(b, t);
    for (i = 0; i < nw && !b->fail; i++) {
        irec in;
        uint32_t s = b->order[i];
        prefetch_ahead(b, i, nw);
        in.P = pend(b->pd, m->frame, b->SR, s, 0);
        in.Q = pend(b->pd, m->frame, b->SR, s, 1);
        in.s = s;
        in.l = b->SR[s].end[0];
        in.r = b->SR[s].end[1];
        SLOTFN(insert_seg)(b, &in);
    }
}
