within StockbridgeDamper.Examples;
model StockbridgeDamper "Stockbridge damper on a shaker: 6-DOF Euler-Bernoulli finite-element model with Bouc-Wen, cubic stiffness and Rayleigh damping; built-in constant-velocity sweep of the clamp"
  extends DamperBase(exc_type=4);
  annotation(experiment(StartTime=0, StopTime=70, Interval=1e-3, Tolerance=1e-8),
    __pyfit(inputDerivatives="x_base:v_base, v_base:a_base"));
end StockbridgeDamper;
