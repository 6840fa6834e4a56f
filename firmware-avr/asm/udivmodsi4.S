; __udivmodsi4: 32-bit unsigned division for the ATmega328P, libgcc's
; restoring shift-subtract loop with its calling convention (dividend in
; r22..r25, divisor in r18..r21; quotient out in r18..r21, remainder in
; r22..r25; uses r26, r27, r30, r31 and r1, left zero), and one change:
; the iterations whose quotient bit is known to be 0 are skipped.
;
; If the quotient is below 2^(32-k) (k = 24, 16, 8), that is if
; dividend >> (32-k) < divisor, the first k iterations only shift the
; dividend's top k bits into the remainder, which stays below the divisor:
; no subtraction, quotient bit 0 each time. So the loop can start there:
; remainder = dividend >> (32-k), the shifted dividend (n << k) with the
; k-1 inverted quotient bits (ones) below it (and under them a bit the
; last pass shifts out unread), carry 1 (the last of them), 33-k passes
; left. One compare per k picks the largest. Same results as libgcc's for
; every input (the `costs` bench checks 4,000 divisions through every
; entry against the host's; the firmware's replays, bit for bit). The
; planner's quotients mostly have 16 bits or fewer: 16 iterations, not 32,
; and those (with divisors below 2^24) take a shorter loop of their own;
; so do quotients of 17 to 24 bits (divisors below 2^16 there), in 17
; passes when the quotient is below 2^17. `cargo xtask avr-profile` counts
; the step's divisions by quotient and divisor length.

	.section .text.libgcc.div,"ax",@progbits
	.global	__udivmodsi4
	.type	__udivmodsi4, @function
__udivmodsi4:
	cp	r23, r18		; dividend >> 8 < divisor: quotient < 2^8
	cpc	r24, r19
	cpc	r25, r20
	cpc	r1, r21			; (r1 is 0)
	brlo	.Lskip24
	cp	r24, r18		; dividend >> 16 < divisor: quotient < 2^16
	cpc	r25, r19		; (the divisor is below 2^24 here: r21 is 0)
	cpc	r1, r20
	brlo	.Lskip16
	cp	r25, r18		; dividend >> 24 < divisor: quotient < 2^24
	cpc	r1, r19			; (the divisor is below 2^16 here)
	brsh	.Lall
	rjmp	.Lskip8			; (out of a branch's reach)
.Lall:
	; All 32 iterations, as libgcc.
	ldi	r26, 33
	mov	r1, r26
	sub	r26, r26		; remainder 0, carry 0
	sub	r27, r27
	movw	r30, r26
	rjmp	.Lep
.Lskip16:
	; Quotient below 2^16 and divisor below 2^24 (r21 is 0): its own loop
	; of 16 passes. The remainder (n >> 16 at first) stays below the
	; divisor, so three bytes hold it (r26, r27, r30), and the dividend's
	; low half shifts out of r22:r23 as the inverted quotient bits shift
	; in. Doubled, the remainder may carry out of its three bytes: then it
	; is above the divisor, and the subtraction's result fits again.
	; About 15.5 cycles a pass against the shared loop's 19.5.
	movw	r26, r24		; remainder = n >> 16
	ldi	r30, 17			; 17 shifts of r22:r23, 16 passes
	mov	r1, r30
	ldi	r30, 0
	rjmp	.L16ep			; (the first bit shifted in is shifted out)
.L16sub:
	sub	r26, r18
	sbc	r27, r19
	sbc	r30, r20
	clc				; quotient bit 1 (inverted: 0)
.L16ep:
	adc	r22, r22		; the inverted quotient bit in, the next dividend bit out
	adc	r23, r23
	dec	r1
	breq	.L16done
	adc	r26, r26		; the dividend's bit into the remainder
	adc	r27, r27
	adc	r30, r30
	brcs	.L16sub			; past 2^24: above the divisor
	cp	r26, r18
	cpc	r27, r19
	cpc	r30, r20
	brcc	.L16sub
	rjmp	.L16ep			; below the divisor: quotient bit 0 (carry 1)
.L16done:
	com	r22			; r1 is 0 again
	com	r23
	movw	r18, r22		; quotient
	ldi	r20, 0
	ldi	r21, 0
	movw	r22, r26		; remainder
	mov	r24, r30
	ldi	r25, 0
	ret
.Lskip24:
	mov	r26, r23		; remainder = n >> 8
	mov	r27, r24
	mov	r30, r25
	ldi	r31, 9
	mov	r1, r31
	ldi	r31, 0
	mov	r25, r22		; n << 24, then 0x7fffff
	ldi	r24, 0x7f
	ldi	r23, 0xff
	ldi	r22, 0xff
	sec
	rjmp	.Lep
.Lloop:
	adc	r26, r26		; the dividend's next bit into the remainder
	adc	r27, r27
	adc	r30, r30
	adc	r31, r31
	cp	r26, r18		; remainder < divisor: quotient bit 0 (carry 1)
	cpc	r27, r19
	cpc	r30, r20
	cpc	r31, r21
	brcs	.Lep
	sub	r26, r18		; else subtract (carry 0: quotient bit 1)
	sbc	r27, r19
	sbc	r30, r20
	sbc	r31, r21
.Lep:
	adc	r22, r22		; the inverted quotient bit in, the next dividend bit out
	adc	r23, r23
	adc	r24, r24
	adc	r25, r25
	dec	r1
	brne	.Lloop
	com	r22			; r1 is 0 again
	com	r23
	com	r24
	com	r25
	movw	r18, r22		; quotient
	movw	r20, r24
	movw	r22, r26		; remainder
	movw	r24, r30
	ret
.Lskip8:
	; Quotient below 2^24 (at least 2^16: the tests above failed) and
	; divisor below 2^16 (r20, r21 are 0): a loop of its own over a
	; two-byte remainder, the dividend's low bits shifting out of
	; r24:r23:r22 as the inverted quotient bits shift in. 17 passes when
	; the quotient is below 2^17 (n >> 17 < divisor: the 1/d² of a near
	; reading), else 24. About 14 cycles a pass against 19.5.
	movw	r26, r24
	lsr	r27
	ror	r26			; n >> 17
	cp	r26, r18
	cpc	r27, r19
	brsh	.L24
	lsr	r24			; the dividend's low 17 bits to the top of
	ror	r23			; r24:r23:r22 (shifted left by 7)
	ror	r22
	mov	r24, r23
	mov	r23, r22
	ldi	r22, 0
	ror	r22
	ldi	r25, 0x01		; the quotient's top byte: one bit
	ldi	r30, 18			; 18 shifts, 17 passes
	rjmp	.L24go
.L24:
	mov	r26, r25		; remainder = n >> 24
	ldi	r27, 0
	ldi	r25, 0xff
	ldi	r30, 25			; 25 shifts, 24 passes
.L24go:
	mov	r1, r30
	rjmp	.L24ep			; (the first bit shifted in is shifted out)
.L24sub:
	sub	r26, r18
	sbc	r27, r19
	clc				; quotient bit 1 (inverted: 0)
.L24ep:
	adc	r22, r22		; the inverted quotient bit in, the next dividend bit out
	adc	r23, r23
	adc	r24, r24
	dec	r1
	breq	.L24done
	adc	r26, r26		; the dividend's bit into the remainder
	adc	r27, r27
	brcs	.L24sub			; past 2^16: above the divisor
	cp	r26, r18
	cpc	r27, r19
	brcc	.L24sub
	rjmp	.L24ep			; below the divisor: quotient bit 0 (carry 1)
.L24done:
	com	r22			; r1 is 0 again
	com	r23
	com	r24
	and	r24, r25
	movw	r18, r22		; quotient
	mov	r20, r24
	ldi	r21, 0
	movw	r22, r26		; remainder
	ldi	r24, 0
	ldi	r25, 0
	ret
	.size	__udivmodsi4, .-__udivmodsi4
