"""The method contract (double_pendulum.solvers.method): every registered method keeps it, and a class
missing a part of it cannot be instantiated."""

from __future__ import annotations

import pytest

from double_pendulum.solvers import METHODS, make_method
from double_pendulum.solvers.method import ABSTRACT_ATTRIBUTES, AdaptiveMethod, Method, contract_violations
from double_pendulum.solvers.runge_kutta import ClassicRK4, Dopri5, hermite_interpolant


@pytest.mark.parametrize("name", sorted(METHODS))
def test_every_registered_method_keeps_the_contract(name):
    method = make_method(name)
    assert isinstance(method, Method)
    assert contract_violations(type(method)) == []
    assert method.name == name
    assert type(method.adaptive) is bool
    assert method.adaptive == isinstance(method, AdaptiveMethod)
    if method.adaptive:
        assert type(method.error_order) is int and 1 <= method.error_order <= method.order
    else:
        assert method.error_order is None
    assert 1 <= method.dense_order <= method.order


@pytest.mark.parametrize("name", sorted(METHODS))
def test_one_step_and_its_dense_output_as_the_contract_says(name):
    """y' = -y from y = 1: the step returns n_stages stages, the interpolant hits both ends."""
    method = make_method(name)

    def f(t, y):
        return [-y[0]]

    y, h = [1.0], 0.01
    y_new, f_new, stages = method.step(f, 0.0, y, f(0.0, y), h)
    assert len(stages) == method.n_stages and method.evals_per_step >= 1
    assert f_new == f(h, y_new)
    assert y_new[0] == pytest.approx(0.990049833749168, rel=1e-4)
    g = method.interpolant(f, 0.0, y, y_new, f(0.0, y), f_new, h, stages)
    assert g(0.0)[0] == pytest.approx(1.0, abs=1e-12) and g(1.0)[0] == pytest.approx(y_new[0], abs=1e-12)
    if method.adaptive:
        assert 0.0 <= method.error_norm(y, y_new, stages, h, 1e-6, 1e-9) < 1.0


def test_the_fixed_step_methods_mark_it_with_adaptive_not_with_error_order_zero():
    fixed = sorted(name for name, cls in METHODS.items() if not cls.adaptive)
    assert fixed == ["euler", "gauss2", "gauss4", "rk4"]
    assert all(METHODS[name].error_order is None for name in fixed)


class _Midpoint(Method):
    """A complete fixed-step method; the classes below each leave out one part of it."""

    name = "midpoint"
    adaptive = False
    order = 2
    error_order = None
    dense_order = 2
    evals_per_step = 2
    dense_evals = 0
    n_stages = 1

    def step(self, f, t, y, fy, h):
        mid = f(t + 0.5 * h, [u + 0.5 * h * d for u, d in zip(y, fy)])
        y_new = [u + h * d for u, d in zip(y, mid)]
        return y_new, f(t + h, y_new), [mid]

    def interpolant(self, f, t, y, y_new, fy, f_new, h, stages):
        return hermite_interpolant(y, y_new, fy, f_new, h)


def test_a_complete_method_outside_the_registry_keeps_it():
    assert contract_violations(_Midpoint) == []
    assert _Midpoint().step(lambda t, y: [0.0], 0.0, [1.0], [0.0], 0.1)[0] == [1.0]


@pytest.mark.parametrize("attribute", ABSTRACT_ATTRIBUTES)
def test_a_method_missing_a_class_attribute_fails(attribute):
    attributes = {k: v for k, v in vars(_Midpoint).items() if k != attribute and not k.startswith("__")}
    incomplete = type("Incomplete", (Method,), attributes)
    assert not hasattr(incomplete, attribute)
    assert f"class attribute {attribute} not defined" in contract_violations(incomplete)
    with pytest.raises(TypeError, match=attribute):
        incomplete()


def test_a_method_missing_step_or_interpolant_fails():
    for missing in ("step", "interpolant"):
        attributes = {k: v for k, v in vars(_Midpoint).items() if k != missing and not k.startswith("__")}
        incomplete = type("Incomplete", (Method,), attributes)
        assert contract_violations(incomplete) == [f"abstract method {missing} not implemented"]
        with pytest.raises(TypeError, match=missing):
            incomplete()


@pytest.mark.parametrize(
    ("changes", "complaint"),
    [
        ({"adaptive": 0}, "adaptive = 0 is not a bool"),
        ({"error_order": 0}, "fixed-step, but error_order = 0 is not None"),
        ({"adaptive": True}, "adaptive, but not an AdaptiveMethod"),
        ({"order": 0}, "order = 0 is not an int >= 1"),
        ({"name": ""}, "name = '' is not a non-empty str"),
        ({"landing_method": ClassicRK4()}, "is not an adaptive method"),
    ],
)
def test_a_method_breaking_a_rule_of_the_contract_fails(changes, complaint):
    broken = type("Broken", (_Midpoint,), changes)
    assert any(complaint in problem for problem in contract_violations(broken)), contract_violations(broken)
    with pytest.raises(TypeError, match="Can't instantiate method Broken"):
        broken()


def test_an_adaptive_method_needs_an_error_norm_and_an_error_order():
    no_norm = type("NoNorm", (AdaptiveMethod,), {k: v for k, v in vars(Dopri5).items() if k != "error_norm"})
    assert contract_violations(no_norm) == ["abstract method error_norm not implemented"]
    no_order = type("NoOrder", (Dopri5,), {"error_order": None})
    assert contract_violations(no_order) == ["adaptive, but error_order = None is not an int >= 1"]
    with pytest.raises(TypeError):
        no_order()


def test_something_that_is_not_a_method_fails():
    assert contract_violations(int) == ["int is not a Method"]
