"""Exudyn multibody systems for the vehicle models, and their time integration in chunks.

Road input without moving the vehicle: the body stays at x = 0 and each tyre reads the road at
the front-axle position s(t) (front) or s(t) - wheelbase (rear), given by a ``Drive``. The tyre
force deviation from the static load is ``k (z - u(s)) + c (z' - v du/ds)``; with ``lift_off``
it is capped at the static load, so the tyre never pulls (unilateral contact).

* ``Jackal``: one planar rigid body with small-angle heave/pitch coordinates [y, phi]
  (``NodeGenericODE2`` + ``ObjectGenericODE2``: mass diag(m, I), the tyres' linear stiffness and
  damping as matrices, the road forcing and the lift-off correction from one Python user function
  per evaluation; this is ~2x faster than a ``NodeRigidBody2D`` with two connector user functions).
* ``HalfCar``: the paper's eq. 1 as a multibody system: the body a ``NodeRigidBody2D`` +
  ``ObjectRigidBody2D``, the axles ``NodePoint2D`` + ``ObjectMassPoint2D``, suspensions
  ``ObjectConnectorCartesianSpringDamper`` (stiffness and damping in y only), tyres Cartesian
  spring-dampers to ground whose force comes from a user function.

Solver: generalised-alpha (spectral radius 0.9), modified Newton, fixed step
1 / (rate_hz * substeps) (Exudyn halves it only where Newton fails).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    MarkerBodyPosition,
    MarkerNodePosition,
    NodeGenericODE2,
    NodePoint2D,
    NodeRigidBody2D,
    ObjectConnectorCartesianSpringDamper,
    ObjectGenericODE2,
    ObjectGround,
    ObjectMassPoint2D,
    ObjectRigidBody2D,
    SensorNode,
)

from roadgen.errors import distinct_texts
from vehicle.errors import SimulationDivergedError
from vehicle.kinematics import Drive
from vehicle.models import HalfCar, Jackal, Model
from vehicle.road_input import RoadInput

_OUT = exu.OutputVariableType
_MAX_ACCEL = 1e4
"""|acceleration| (m/s^2) above which a run counts as diverged."""
_MAX_DISPLACEMENT = 1.0
"""|heave| or |axle displacement| (m) from the static equilibrium on the road under the wheels
above which a run counts as diverged (so a road's offset or grade is no divergence)."""


@dataclass(frozen=True)
class States:
    """Sampled states at the sample instants, each (n,); SI units.

    t: time, s. accel_front, accel_rear: vertical axle accelerations, m/s^2. heave (m), pitch
    (rad, nose up positive) of the body. z_front, z_rear (m), zt_front, zt_rear (m/s): vertical
    axle displacement and velocity (where the tyre force acts).
    """

    t: np.ndarray
    accel_front: np.ndarray
    accel_rear: np.ndarray
    heave: np.ndarray
    pitch: np.ndarray
    z_front: np.ndarray
    z_rear: np.ndarray
    zt_front: np.ndarray
    zt_rear: np.ndarray


class _TyreInput:
    """The road under each tyre on the drive's time grid, as the user functions read it.

    ``data = (t0, 1/h, N - 1, u_front, w_front, u_rear, w_rear)``: lists (N + 1,) of the road
    height u (m) and of its rate w = v du/ds (m/s) under each axle at t0 + k h. Tabulated once
    per chunk (vectorised), so a user-function call only interpolates in time.
    """

    def __init__(self) -> None:
        self.data: tuple = ()

    def update(self, drive: Drive, road: RoadInput, wheelbase_m: float) -> None:
        s, v = drive.s, drive.v
        rows = []
        for pos in (s, s - wheelbase_m):
            rows += [road.heights(pos).tolist(), (v * road.slopes(pos)).tolist()]
        self.data = (drive.t0, 1.0 / drive.h, s.size - 2, *rows)


class ExudynVehicle:
    """An assembled Exudyn system for ``model`` on ``road``, integrated chunk by chunk.

    Args:
        model: HalfCar or Jackal. road: RoadInput. drive: the front axle's s(t), v(t) (its grid
            is replaced between chunks). rate_hz: sample rate. substeps: solver steps per sample.

    The vehicle starts at rest with its axles on the road heights at the drive's first position.
    """

    def __init__(
        self, model: Model, road: RoadInput, drive: Drive, rate_hz: float, substeps: int
    ) -> None:
        s0 = float(drive.s[0])
        self._u0 = tuple(float(u) for u in road.heights(np.array([s0, s0 - model.wheelbase_m])))
        self._input = _TyreInput()
        self.model = model
        self.road = road
        self.drive = drive
        self.rate_hz = float(rate_hz)
        self.substeps = int(substeps)
        self.sc = exu.SystemContainer()
        self.mbs = self.sc.AddSystem()
        if isinstance(model, Jackal):
            self._read = self._build_jackal()
        else:
            self._read = self._build_halfcar()
        self.mbs.Assemble()
        self.settings = self._settings()

    def _settings(self) -> exu.SimulationSettings:
        ss = exu.SimulationSettings()
        ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
        ss.timeIntegration.newton.useModifiedNewton = True
        # 1e-6 (default 1e-8) saves the last Newton iteration: 2 instead of 3 force evaluations
        # per step; bilateral traces are unchanged, lift-off ones change by ~0.3 % RMS
        ss.timeIntegration.newton.relativeTolerance = 1e-6
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        ss.solution.sensors.writePeriod = (1.0 / self.rate_hz) * (1.0 - 1e-9)
        return ss

    def _tyre_loads(self) -> tuple[float, float]:
        if not self.model.lift_off:
            return float("inf"), float("inf")
        return self.model.static_tyre_loads_n

    def _build_jackal(self):
        m: Jackal = self.model
        mbs = self.mbs
        k, c = m.axle_stiffness_n_per_m, m.axle_damping_ns_per_m
        b1, b2, wb = m.b1_m, m.b2_m, m.wheelbase_m
        f1s, f2s = self._tyre_loads()
        u1, u2 = self._u0
        phi0 = (u1 - u2) / wb
        y0 = u1 - b1 * phi0
        stiff = np.array([[2 * k, k * (b1 - b2)], [k * (b1 - b2), k * (b1 * b1 + b2 * b2)]])
        node = mbs.AddNode(
            NodeGenericODE2(
                referenceCoordinates=[0.0, 0.0],
                initialCoordinates=[y0, phi0],
                initialCoordinates_t=[0.0, 0.0],
                numberOfODE2Coordinates=2,
            )
        )
        table = self._input

        def road_force(mbs_, t, item, q, q_t):
            # runs 2-4 times per solver step: plain floats and lists, no numpy
            t0, inv_h, last, u1s, w1s, u2s, w2s = table.data
            r = (t - t0) * inv_h
            i = int(r)
            i = 0 if i < 0 else (last if i > last else i)
            w = r - i
            f1 = k * (u1s[i] + w * (u1s[i + 1] - u1s[i])) + c * (w1s[i] + w * (w1s[i + 1] - w1s[i]))
            f2 = k * (u2s[i] + w * (u2s[i + 1] - u2s[i])) + c * (w2s[i] + w * (w2s[i + 1] - w2s[i]))
            q0, q1, qt0, qt1 = q[0], q[1], q_t[0], q_t[1]
            lin1 = f1 - k * (q0 + b1 * q1) - c * (qt0 + b1 * qt1)
            if lin1 < -f1s:
                f1 -= lin1 + f1s
            lin2 = f2 - k * (q0 - b2 * q1) - c * (qt0 - b2 * qt1)
            if lin2 < -f2s:
                f2 -= lin2 + f2s
            return [f1 + f2, b1 * f1 - b2 * f2]

        mbs.AddObject(
            ObjectGenericODE2(
                nodeNumbers=[node],
                massMatrix=exu.MatrixContainer(np.diag([m.mass_kg, m.pitch_inertia_kgm2])),
                stiffnessMatrix=exu.MatrixContainer(stiff),
                dampingMatrix=exu.MatrixContainer(stiff * (c / k)),
                forceUserFunction=road_force,
            )
        )
        sensors = [
            mbs.AddSensor(
                SensorNode(
                    nodeNumber=node, outputVariableType=o, storeInternal=True, writeToFile=False
                )
            )
            for o in (_OUT.Coordinates, _OUT.Coordinates_t, _OUT.Coordinates_tt)
        ]

        def read() -> tuple[np.ndarray, dict[str, np.ndarray]]:
            q, qt, qtt = (mbs.GetSensorStoredData(s) for s in sensors)
            return q[:, 0], {
                "accel_front": qtt[:, 1] + b1 * qtt[:, 2],
                "accel_rear": qtt[:, 1] - b2 * qtt[:, 2],
                "heave": q[:, 1],
                "pitch": q[:, 2],
                "z_front": q[:, 1] + b1 * q[:, 2],
                "z_rear": q[:, 1] - b2 * q[:, 2],
                "zt_front": qt[:, 1] + b1 * qt[:, 2],
                "zt_rear": qt[:, 1] - b2 * qt[:, 2],
            }

        return read

    def _build_halfcar(self):
        m: HalfCar = self.model
        mbs = self.mbs
        b1, b2, wb = m.b1_m, m.b2_m, m.wheelbase_m
        kt, ct = m.tyre_stiffness_n_per_m, m.tyre_damping_ns_per_m
        f1s, f2s = self._tyre_loads()
        u1, u2 = self._u0
        phi0 = (u1 - u2) / wb
        ground = mbs.AddObject(ObjectGround())
        body_node = mbs.AddNode(
            NodeRigidBody2D(
                referenceCoordinates=[0.0, 0.0, 0.0],
                initialCoordinates=[0.0, u1 - b1 * phi0, phi0],
            )
        )
        body = mbs.AddObject(
            ObjectRigidBody2D(
                nodeNumber=body_node, mass=m.sprung_mass_kg, inertia=m.pitch_inertia_kgm2
            )
        )
        axles = []
        for axle, x_axle, m_u, k_s, c_s, f_static, u0 in (
            (0, b1, m.unsprung_mass_front_kg, m.suspension_stiffness_front_n_per_m,
             m.suspension_damping_front_ns_per_m, f1s, u1),
            (1, -b2, m.unsprung_mass_rear_kg, m.suspension_stiffness_rear_n_per_m,
             m.suspension_damping_rear_ns_per_m, f2s, u2),
        ):  # fmt: skip
            node = mbs.AddNode(
                NodePoint2D(referenceCoordinates=[x_axle, 0.0], initialCoordinates=[0.0, u0])
            )
            mbs.AddObject(ObjectMassPoint2D(nodeNumber=node, mass=m_u))
            axle_marker = mbs.AddMarker(MarkerNodePosition(nodeNumber=node))
            body_marker = mbs.AddMarker(
                MarkerBodyPosition(bodyNumber=body, localPosition=[x_axle, 0.0, 0.0])
            )
            ground_marker = mbs.AddMarker(
                MarkerBodyPosition(bodyNumber=ground, localPosition=[x_axle, 0.0, 0.0])
            )
            mbs.AddObject(
                ObjectConnectorCartesianSpringDamper(
                    markerNumbers=[body_marker, axle_marker],
                    stiffness=[0.0, k_s, 0.0],
                    damping=[0.0, c_s, 0.0],
                )
            )
            mbs.AddObject(
                ObjectConnectorCartesianSpringDamper(
                    markerNumbers=[ground_marker, axle_marker],
                    stiffness=[0.0, kt, 0.0],
                    damping=[0.0, ct, 0.0],
                    springForceUserFunction=_tyre_function(self._input, axle, kt, ct, f_static),
                )
            )
            axles.append(node)
        sens = {
            (name, o): mbs.AddSensor(
                SensorNode(
                    nodeNumber=n, outputVariableType=o, storeInternal=True, writeToFile=False
                )
            )
            for name, n in (("front", axles[0]), ("rear", axles[1]))
            for o in (_OUT.Displacement, _OUT.Velocity, _OUT.Acceleration)
        }
        body_sensor = mbs.AddSensor(
            SensorNode(
                nodeNumber=body_node,
                outputVariableType=_OUT.Coordinates,
                storeInternal=True,
                writeToFile=False,
            )
        )

        def read() -> tuple[np.ndarray, dict[str, np.ndarray]]:
            get = mbs.GetSensorStoredData
            q = get(body_sensor)
            out = {"heave": q[:, 2], "pitch": q[:, 3]}
            for name in ("front", "rear"):
                out[f"z_{name}"] = get(sens[name, _OUT.Displacement])[:, 2]
                out[f"zt_{name}"] = get(sens[name, _OUT.Velocity])[:, 2]
                out[f"accel_{name}"] = get(sens[name, _OUT.Acceleration])[:, 2]
            return q[:, 0], out

        return read

    def integrate(self, t_start: float, n_samples: int) -> States:
        """Integrate from ``t_start`` over ``n_samples`` sample periods, continuing the state.

        Returns the states at t_start + j / rate_hz, j = 1..n_samples. Raises
        SimulationDivergedError if the solver fails or the states leave their valid range, and
        KeyboardInterrupt where Ctrl-C stopped the solver (inside a user function: Exudyn
        reports it as a RuntimeError)."""
        self._input.update(self.drive, self.road, self.model.wheelbase_m)
        ti = self.settings.timeIntegration
        ti.startTime = t_start
        ti.endTime = t_start + n_samples / self.rate_hz
        ti.numberOfSteps = n_samples * self.substeps
        printing = exu.config.printToConsole
        exu.config.printToConsole = False  # the solver's hints and warnings are not ours to print
        try:
            ok = self.mbs.SolveDynamic(self.settings, updateInitialValues=True)
        except (RuntimeError, ValueError) as exc:
            if _INTERRUPTED.search(str(exc)):  # Ctrl-C inside a user function: no divergence
                raise KeyboardInterrupt(f"the solver, near t={t_start:.4g} s") from exc
            raise SimulationDivergedError(
                f"Exudyn solver failed near t={t_start:.4g} s: {exc}"
            ) from exc
        finally:
            exu.config.printToConsole = printing
        if not ok:
            raise SimulationDivergedError(
                f"Exudyn solver failed between t={t_start:.4g} s and t={ti.endTime:.4g} s"
            )
        t, out = self._read()
        k = np.rint((t - t_start) * self.rate_hz).astype(int)
        _, keep = np.unique(k, return_index=True)
        keep = keep[(k[keep] >= 1) & (k[keep] <= n_samples)]
        if keep.size != n_samples:
            raise SimulationDivergedError(
                f"got {keep.size} of {n_samples} samples after t={t_start:.4g} s"
            )
        states = States(t=t_start + k[keep] / self.rate_hz, **{n: a[keep] for n, a in out.items()})
        _check_finite(states)
        s = self.drive.positions(states.t)
        u = self.road.heights(np.stack([s, s - self.model.wheelbase_m]))
        _check_range(states, self.model, u[0], u[1])
        return states


_INTERRUPTED = re.compile(r"^KeyboardInterrupt\b", re.MULTILINE)
"""How Exudyn reports a KeyboardInterrupt raised in a Python user function (Ctrl-C lands there,
the solver calling the road forces all the time): "Error in Python USER FUNCTION '...':" and
the exception's type and message on the next line, in the RuntimeError it raises instead."""


def _tyre_function(table: _TyreInput, axle: int, k: float, c: float, f_static: float):
    """Cartesian spring-damper user function of one tyre: force [0, f, 0], f <= f_static."""

    def tyre(mbs, t, item, displacement, velocity, stiffness, damping, off):
        t0, inv_h, last = table.data[:3]
        us, ws = table.data[3 + 2 * axle : 5 + 2 * axle]
        r = (t - t0) * inv_h
        i = int(r)
        i = 0 if i < 0 else (last if i > last else i)
        w = r - i
        u = us[i] + w * (us[i + 1] - us[i])
        f = k * (displacement[1] - u) + c * (velocity[1] - (ws[i] + w * (ws[i + 1] - ws[i])))
        if f > f_static:
            f = f_static
        return [0.0, f, 0.0]

    return tyre


def _check_finite(st: States) -> None:
    """Raise SimulationDivergedError if an acceleration or a displacement is NaN or inf."""
    states = np.concatenate([st.accel_front, st.accel_rear, st.heave, st.z_front, st.z_rear])
    if not np.all(np.isfinite(states)):
        raise SimulationDivergedError(
            f"NaN/inf states between t={st.t[0]:.4g} and {st.t[-1]:.4g} s"
        )


def _check_range(st: States, model: Model, u_front: np.ndarray, u_rear: np.ndarray) -> None:
    """Raise SimulationDivergedError if an |acceleration| exceeds ``_MAX_ACCEL`` or the body or
    an axle lies more than ``_MAX_DISPLACEMENT`` from its static equilibrium, which follows the
    road heights under the axles (``u_front``, ``u_rear``, m; the body's at its centre of mass).
    """
    u_body = (model.b2_m * u_front + model.b1_m * u_rear) / model.wheelbase_m
    accel = np.concatenate([st.accel_front, st.accel_rear])
    disp = np.concatenate([st.heave - u_body, st.z_front - u_front, st.z_rear - u_rear])
    peak_accel, peak_disp = np.max(np.abs(accel)), np.max(np.abs(disp))
    if peak_accel > _MAX_ACCEL or peak_disp > _MAX_DISPLACEMENT:
        raise SimulationDivergedError(
            f"states out of range between t={st.t[0]:.4g} and {st.t[-1]:.4g} s: "
            f"max |accel| {distinct_texts(peak_accel, _MAX_ACCEL, digits=3)[0]} m/s^2 "
            f"(limit {_MAX_ACCEL:g}), max |displacement| from the road "
            f"{distinct_texts(peak_disp, _MAX_DISPLACEMENT, digits=3)[0]} m "
            f"(limit {_MAX_DISPLACEMENT:g})"
        )
