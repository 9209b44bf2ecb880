"""The 3-D pages of Python results: written, self-contained, their frames stated."""

from __future__ import annotations

import pathlib
import re

import numpy as np
import pytest

import liemid
import liemid.many
import liemid.spins


def _self_contained(text: str) -> None:
    assert text.startswith("<!DOCTYPE html>")
    assert not re.search(r"""(?i)(src|href)\s*=\s*["']?https?:""", text)
    assert "<script src" not in text


def test_solution_view_writes_a_page(tmp_path: pathlib.Path) -> None:
    body = liemid.RigidBody(inertia=[1.0, 2.0, 3.0])
    sol = liemid.integrate(body, t_end=1.0, step=0.01, angular_velocity=[0.1, 10.0, 0.0])
    path = tmp_path / "rigid.html"
    assert sol.view(str(path)) == str(path)
    text = path.read_text()
    _self_contained(text)
    assert f"{len(sol.t)} frames of {sol.steps} steps" in text
    inline = sol._repr_html_()
    assert inline.startswith("<iframe srcdoc=")


def test_many_and_spins_views(tmp_path: pathlib.Path) -> None:
    system = liemid.many.System.dipolar_fluid(27, density=0.3)
    text = system.view()
    _self_contained(text)
    assert "1 frames of 0 steps" in text
    spin_system, spins = liemid.spins.problem("square-64")
    run = liemid.spins.integrate(spin_system, spins, t_end=0.1, step=0.01, every=2)
    path = tmp_path / "spins.html"
    run.view(spin_system, str(path))
    _self_contained(path.read_text())
    assert np.isfinite(run.energy).all()


def test_beam_and_multibody_pages(tmp_path: pathlib.Path) -> None:
    from liemid import beam, multibody

    run = beam.run("right-angle-cantilever", elements_per_member=2, t_end=1.0, sample=0.1, view=True)
    page = run.view()
    assert page.startswith("<!DOCTYPE html>") and '"beam"' in page and "frames of" in page
    assert run.view(str(tmp_path / "b.html")) == str(tmp_path / "b.html")
    assert "<iframe" in (run._repr_html_() or "")
    with pytest.raises(ValueError, match="view=True"):
        beam.run("right-angle-cantilever", elements_per_member=2, t_end=0.5).view()
    mb = multibody.problem("double-pendulum").run(step=1e-3, t_end=1.0, every=10)
    html = mb.view()
    assert '"articulated"' in html and "101 frames of 1000 steps" in html
    assert "<iframe" in mb._repr_html_()
