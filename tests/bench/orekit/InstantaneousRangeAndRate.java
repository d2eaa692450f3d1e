package tappbench;

import java.util.Collections;

import org.hipparchus.geometry.euclidean.threed.Vector3D;
import org.orekit.estimation.measurements.AbstractMeasurement;
import org.orekit.estimation.measurements.EstimatedMeasurement;
import org.orekit.estimation.measurements.EstimatedMeasurementBase;
import org.orekit.estimation.measurements.ObservableSatellite;
import org.orekit.frames.TopocentricFrame;
import org.orekit.propagation.SpacecraftState;
import org.orekit.time.AbsoluteDate;
import org.orekit.utils.TimeStampedPVCoordinates;

/**
 * Instantaneous range (m) and range rate (m/s) of a spacecraft from a ground station: the
 * measurement tapp's differential corrector fits, with no light time.
 *
 * <p>Orekit 13's own Range and RangeRate always solve the light time (it cannot be switched
 * off), and tapp's DC has none; this class is Orekit's two measurements with the signal
 * taken as instantaneous, so that both estimators fit one model. Values and partials:
 * rho = |r - r_st|, u = (r - r_st) / rho, rhoDot = u . (v - v_st);
 * d rho / d r = u, d rho / d v = 0; d rhoDot / d r = (v - v_st - rhoDot u) / rho,
 * d rhoDot / d v = u, with the station's state (position and velocity) in the spacecraft
 * state's frame from Orekit's Earth frame (its IERS 2010 ITRF with the EOP it was given).
 */
public class InstantaneousRangeAndRate extends AbstractMeasurement<InstantaneousRangeAndRate> {

    /** The station: a point fixed in the Earth frame. */
    private final TopocentricFrame station;

    /**
     * A range and range-rate pair received at {@code date}.
     *
     * @param station ground station
     * @param date reception date
     * @param range observed range, m
     * @param rangeRate observed range rate, m/s
     * @param sigmaRange standard deviation of the range, m
     * @param sigmaRangeRate standard deviation of the range rate, m/s
     * @param satellite the observed satellite
     */
    public InstantaneousRangeAndRate(final TopocentricFrame station, final AbsoluteDate date,
                                     final double range, final double rangeRate,
                                     final double sigmaRange, final double sigmaRangeRate,
                                     final ObservableSatellite satellite) {
        super(date, new double[] {range, rangeRate}, new double[] {sigmaRange, sigmaRangeRate},
              new double[] {1.0, 1.0}, Collections.singletonList(satellite));
        this.station = station;
    }

    /** @return the station */
    public TopocentricFrame getStation() {
        return station;
    }

    @Override
    protected EstimatedMeasurementBase<InstantaneousRangeAndRate> theoreticalEvaluationWithoutDerivatives(
            final int iteration, final int evaluation, final SpacecraftState[] states) {
        return evaluate(iteration, evaluation, states, false);
    }

    @Override
    protected EstimatedMeasurement<InstantaneousRangeAndRate> theoreticalEvaluation(
            final int iteration, final int evaluation, final SpacecraftState[] states) {
        return evaluate(iteration, evaluation, states, true);
    }

    private EstimatedMeasurement<InstantaneousRangeAndRate> evaluate(
            final int iteration, final int evaluation, final SpacecraftState[] states,
            final boolean partials) {
        final SpacecraftState state = states[0];
        final TimeStampedPVCoordinates craft = state.getPVCoordinates();
        final TimeStampedPVCoordinates site = station.getPVCoordinates(state.getDate(),
                                                                       state.getFrame());
        final Vector3D dr = craft.getPosition().subtract(site.getPosition());
        final Vector3D dv = craft.getVelocity().subtract(site.getVelocity());
        final double rho = dr.getNorm();
        final Vector3D u = dr.scalarMultiply(1.0 / rho);
        final double rhoDot = Vector3D.dotProduct(u, dv);
        final EstimatedMeasurement<InstantaneousRangeAndRate> estimated =
            new EstimatedMeasurement<>(this, iteration, evaluation, states,
                                       new TimeStampedPVCoordinates[] {site, craft});
        estimated.setEstimatedValue(rho, rhoDot);
        if (partials) {
            final Vector3D w = dv.subtract(rhoDot, u).scalarMultiply(1.0 / rho);
            estimated.setStateDerivatives(0,
                new double[] {u.getX(), u.getY(), u.getZ(), 0.0, 0.0, 0.0},
                new double[] {w.getX(), w.getY(), w.getZ(), u.getX(), u.getY(), u.getZ()});
        }
        return estimated;
    }

}
