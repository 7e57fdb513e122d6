#!/usr/bin/env python3
"""Exact symbolic recovery check, following the SRBench rule.

A model recovers the ground truth when, after every numeric constant on
both sides is rounded to 3 significant digits and the expressions are
simplified, either
    truth - model   is a constant, or
    model / truth   is a nonzero constant.

Single check (prints `true` or `false`, exit 0; exit 2 on a parse error):
    python srbench_check.py --truth "mu*Nn" --model "mu*Nn + 3.2" [--vars mu,Nn]

Batch check (FILE is a JSON list of {"truth", "model"[, "vars"]}; prints a
JSON list of booleans, one per item; an item whose model does not parse
counts as false, with a note on stderr):
    python srbench_check.py --batch FILE.json

Choices that differ from, or go beyond, SRBench's own script:
  * SRBench rounds the floats of (truth - model), after writing pi in the
    truth as 3.1415926535, to a fixed number of decimal places. Here both
    sides are first evaluated numerically (pi, 1/3, sqrt(2) become floats),
    then every float is rounded to 3 significant digits and made an exact
    Rational, so 0.500*x and x/2 cancel exactly inside simplify. Rounding
    the truth as well is what lets a model match a truth with an irrational
    constant inside a nonlinear function, e.g. exp(h*omega/(2*pi*kb*T)).
  * Every variable is a positive real Symbol: all Feynman inputs are sampled
    from positive ranges, and the assumption lets simplify use identities
    such as sqrt(x**2) = x that hold on the data's domain.
  * SRBench only checks models whose test R^2 exceeds 0.5; that gate is left
    to the caller.
  * simplify can run for a very long time on bloated GP models, so each check
    runs under a wall-clock alarm (default 30 s); a timeout counts as false.
"""

import argparse
import json
import re
import signal
import sys
from contextlib import contextmanager

import sympy
from sympy.parsing.sympy_parser import parse_expr

SIGNIFICANT_DIGITS = 3
DEFAULT_TIMEOUT_S = 30.0

# Names that are operations or constants rather than variables, including
# those that str() of a sympy expression can print. Every other identifier is
# a variable; mapping it explicitly keeps sympy from reading names such as
# `beta`, `gamma` or `S` as its own objects. Variables named explicitly
# (--vars, or "vars" in a batch item) take precedence over these.
_KNOWN_NAMES = {
    "sqrt": sympy.sqrt,
    "log": sympy.log,
    "exp": sympy.exp,
    "tanh": sympy.tanh,
    "Abs": sympy.Abs,
    "pi": sympy.pi,
    "E": sympy.E,
    "I": sympy.I,
    "oo": sympy.oo,
    "zoo": sympy.zoo,
    "nan": sympy.nan,
    "Rational": sympy.Rational,
    "Integer": sympy.Integer,
    "Float": sympy.Float,
}
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


class CheckTimeout(Exception):
    pass


@contextmanager
def _alarm(seconds):
    """Raises CheckTimeout in the main thread after `seconds` of wall time."""
    def on_alarm(signum, frame):
        raise CheckTimeout()

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def parse(text, variables=None):
    """Parses `text` with every variable as a positive Symbol.

    `variables` names the variables explicitly; without it, every identifier
    that is not a known operation or constant is taken as a variable.
    Raises ValueError when the text does not parse.
    """
    names = set(variables or ()) | {
        n for n in _IDENTIFIER.findall(text) if n not in _KNOWN_NAMES
    }
    local = dict(_KNOWN_NAMES)
    local.update({n: sympy.Symbol(n, positive=True) for n in names})
    try:
        expr = parse_expr(text, local_dict=local)
    except Exception as e:  # sympy raises many types for malformed input
        raise ValueError(f"cannot parse {text!r}: {e}") from e
    if not isinstance(expr, sympy.Expr):
        raise ValueError(f"{text!r} is not an expression")
    return expr


def _numbers_to_floats(expr):
    """Turns every non-integer numeric constant (pi, 1/3, sqrt(2), ...) into
    a Float, at any depth; evalf alone leaves those inside exp() alone."""
    if expr.is_number and not expr.is_Integer:
        value = expr.evalf(15)
        return value if value.is_Float else expr
    if expr.is_Atom:
        return expr
    return expr.func(*[_numbers_to_floats(a) for a in expr.args])


def round_constants(expr, digits=SIGNIFICANT_DIGITS):
    """Replaces each non-integer numeric constant of `expr` by its value
    rounded to `digits` significant digits, as an exact Rational."""
    expr = _numbers_to_floats(expr)
    replacements = {
        f: sympy.Rational(format(float(f), f".{digits}g"))
        for f in expr.atoms(sympy.Float)
    }
    return expr.xreplace(replacements)


def _is_constant(expr, nonzero=False):
    if expr.has(sympy.nan, sympy.zoo, sympy.oo, -sympy.oo):
        return False
    if expr.free_symbols:
        # simplify can miss an identity; is_constant probes numerically and
        # answers None when it cannot decide, which counts as not constant.
        if expr.is_constant(simplify=False) is not True:
            return False
    return not (nonzero and expr.is_zero)


def is_recovered(truth, model, timeout_s=DEFAULT_TIMEOUT_S):
    """Applies the recovery rule to two sympy expressions.

    Returns (recovered, note); the note says why a check was cut short.
    """
    truth = round_constants(truth)
    model = round_constants(model)
    try:
        with _alarm(timeout_s):
            if _is_constant(sympy.simplify(truth - model)):
                return True, ""
            return _is_constant(sympy.simplify(model / truth), nonzero=True), ""
    except CheckTimeout:
        return False, f"simplify timed out after {timeout_s:g} s"


def check_strings(truth, model, variables=None, timeout_s=DEFAULT_TIMEOUT_S):
    """String front end to is_recovered; parse errors raise ValueError."""
    return is_recovered(parse(truth, variables), parse(model, variables),
                        timeout_s)


def _run_batch(path, timeout_s):
    try:
        with open(path) as f:
            items = json.load(f)
        if not isinstance(items, list):
            raise ValueError("batch file must hold a JSON list")
    except (OSError, ValueError) as e:
        print(f"error: {path}: {e}", file=sys.stderr)
        return 2
    results = []
    for i, item in enumerate(items):
        try:
            ok, note = check_strings(item["truth"], item["model"],
                                     item.get("vars"), timeout_s)
        except (KeyError, TypeError, ValueError) as e:
            ok, note = False, f"bad item: {e}"
        if note:
            print(f"note: item {i}: {note}", file=sys.stderr)
        results.append(ok)
    print(json.dumps(results))
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--truth", help="ground-truth expression (sympy syntax)")
    ap.add_argument("--model", help="model expression (sympy syntax)")
    ap.add_argument("--vars", help="comma-separated variable names")
    ap.add_argument("--batch", metavar="FILE.json",
                    help="JSON list of {truth, model[, vars]} objects")
    ap.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT_S,
                    help="seconds allowed for simplify per check "
                         "(default %(default)s)")
    args = ap.parse_args(argv)

    if args.batch:
        return _run_batch(args.batch, args.timeout)
    if args.truth is None or args.model is None:
        ap.error("give --truth and --model, or --batch")
    variables = args.vars.split(",") if args.vars else None
    try:
        ok, note = check_strings(args.truth, args.model, variables,
                                 args.timeout)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if note:
        print(f"note: {note}", file=sys.stderr)
    print("true" if ok else "false")
    return 0


if __name__ == "__main__":
    sys.exit(main())
