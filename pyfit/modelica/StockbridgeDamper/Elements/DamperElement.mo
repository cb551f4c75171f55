within StockbridgeDamper.Elements;
model DamperElement "The Stockbridge damper (theory §1.3) as an element: clamp motion x_base, v_base, a_base in; clamp force F_clamp out (no built-in excitation by default)"
  extends Examples.DamperBase(exc_type=0);
  annotation(__pyfit(inputDerivatives="x_base:v_base, v_base:a_base"), experiment(StartTime=0, StopTime=1, Interval=1e-4, Tolerance=1e-8));
end DamperElement;
